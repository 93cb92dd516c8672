// The views of a desktop frame: one eye filling the canvas, or side-by-side stereo (two
// parallel eyes ipd apart along the camera's right vector, as the core's StereoCamera, each
// in one half of the canvas with the same vertical field of view). Both go through the same
// per-view draw as the XR eyes.

import { makeView, shifted } from './camera.js';

export const DEFAULT_IPD = 0.064;

// frame: camera.js frame of the centre eye; fov: vertical degrees; canvas size in pixels.
export function desktopViews(frame, fov, width, height, stereo = false, ipd = DEFAULT_IPD) {
  if (!stereo) return [makeView(frame, fov, [0, 0, width, height])];
  const half = Math.floor(width / 2);
  return [
    makeView(shifted(frame, -0.5 * ipd), fov, [0, 0, half, height]),
    makeView(shifted(frame, 0.5 * ipd), fov, [half, 0, width - half, height]),
  ];
}

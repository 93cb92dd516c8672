// The core's pinhole camera (cpp/views/camera.h) as WebGL matrices.
//
// Convention of `gigascroll render --camera EX,EY,EZ,TX,TY,TZ[,FOV]`: world y is up, forward =
// normalize(target - eye), right = normalize(forward x up), true up = right x forward; FOV is
// the vertical field of view in degrees, tan_half_x = tan_half_y * width / height (square
// pixels). The core casts its ray for pixel (px, py) (py down from the top) through
// forward + (2 (px + 0.5) / W - 1) tan_half_x right + (1 - 2 (py + 0.5) / H) tan_half_y up,
// which is exactly where GL's viewport transform puts the centre of that fragment when the
// projection below maps x_eye / z_eye = tan_half_x to NDC x = 1 (GL rows count from the bottom,
// so a read-back frame is flipped vertically to compare with the core's image).
//
// Matrices are column-major Float32Array(16), as WebGL and WebXR hand them out.

export const DEFAULT_FOV = 60;
export const NEAR = 0.05;  // 24-bit depth keeps a painting 5 mm off its wall apart at 20 m
export const FAR = 200;

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const normalize = (a) => scale(a, 1 / Math.hypot(a[0], a[1], a[2]));
export const vec3 = { sub, dot, cross, scale, normalize, add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]] };

// The frame of Camera::look_at: {position, forward, right, up}, all unit and orthogonal.
export function lookAt(eye, target, worldUp = [0, 1, 0]) {
  const forward = normalize(sub(target, eye));
  const r = cross(forward, worldUp);
  if (!(Math.hypot(...r) > 1e-6)) throw new Error('camera: up is parallel to the viewing direction');
  const right = normalize(r);
  return { position: [...eye], forward, right, up: cross(right, forward) };
}

// The frame seen from yaw (about world y, 0 = looking along -z) and pitch (radians).
export function frameFromAngles(position, yaw, pitch) {
  const c = Math.cos(pitch);
  const forward = [-Math.sin(yaw) * c, Math.sin(pitch), -Math.cos(yaw) * c];
  return lookAt(position, [position[0] + forward[0], position[1] + forward[1], position[2] + forward[2]]);
}

// Yaw and pitch of a frame's forward vector (the inverse of frameFromAngles).
export function anglesOf(frame) {
  const f = frame.forward;
  return { yaw: Math.atan2(-f[0], -f[2]), pitch: Math.asin(Math.max(-1, Math.min(1, f[1]))) };
}

// World -> eye matrix: rows right, up, -forward; the eye looks down its -z.
export function viewMatrix(frame) {
  const { position: p, right: r, up: u, forward: f } = frame;
  return new Float32Array([
    r[0], u[0], -f[0], 0,
    r[1], u[1], -f[1], 0,
    r[2], u[2], -f[2], 0,
    -dot(r, p), -dot(u, p), dot(f, p), 1,
  ]);
}

// Symmetric perspective: x_eye / -z_eye = tanHalfX maps to NDC x = 1 (and y alike).
export function projection(tanHalfX, tanHalfY, near = NEAR, far = FAR) {
  const a = (far + near) / (near - far), b = (2 * far * near) / (near - far);
  return new Float32Array([
    1 / tanHalfX, 0, 0, 0,
    0, 1 / tanHalfY, 0, 0,
    0, 0, a, -1,
    0, 0, b, 0,
  ]);
}

// tan_half_y and tan_half_x as Camera::look_at computes them (single precision).
export function tangents(fovYDeg, width, height) {
  const f = Math.fround, angle = f(f(f(0.5 * f(fovYDeg)) * f(Math.PI)) / 180);
  const t = f(Math.tan(angle));
  return { tanHalfX: t * f(width / height), tanHalfY: t };
}

export function multiply(a, b) {
  const out = new Float32Array(16);
  for (let c = 0; c < 4; c++)
    for (let r = 0; r < 4; r++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      out[c * 4 + r] = s;
    }
  return out;
}

// One view to draw, the unit the whole client passes around (desktop eye, stereo eye, XR eye,
// magnifier): world -> eye and eye -> clip matrices, the eye's position (for picking the lit
// side of a surface) and the pixel rectangle [x, y, w, h] (GL's, from the bottom) it fills.
export function makeView(frame, fovYDeg, viewport) {
  const { tanHalfX, tanHalfY } = tangents(fovYDeg, viewport[2], viewport[3]);
  return { view: viewMatrix(frame), proj: projection(tanHalfX, tanHalfY), position: [...frame.position],
           frame, viewport: [...viewport], tanHalfY };
}

const MAX_COORDINATE = 1e12;   // the core camera's bound on a position (cpp/views/camera.cpp)

// `?camera=x,y,z,tx,ty,tz[,fov]` as `render --camera` reads it; null when absent. Throws on a
// malformed value (the page shows the message) rather than silently drawing another view.
export function parseCameraParam(search) {
  const text = new URLSearchParams(search).get('camera');
  if (text === null) return null;
  const v = text.split(',').map((s) => (s.trim() === '' ? NaN : Number(s)));
  if ((v.length !== 6 && v.length !== 7) || !v.every(Number.isFinite))
    throw new Error(`?camera wants x,y,z,tx,ty,tz[,fov] finite numbers, got "${text}"`);
  if (v.slice(0, 6).some((x) => Math.abs(x) > MAX_COORDINATE))
    throw new Error(`?camera: eye and target must be within +-1e12 m (render --camera's limit), got "${text}"`);
  const fov = v.length === 7 ? v[6] : DEFAULT_FOV;
  if (!(fov > 0 && fov < 180)) throw new Error(`?camera: the field of view must be in (0, 180), got ${fov}`);
  const eye = v.slice(0, 3), target = v.slice(3, 6);
  if (eye.every((x, i) => x === target[i])) throw new Error('?camera: eye and target must differ');
  return { eye, target, fov };
}

// A frame moved along its own right vector (a stereo eye: the core's StereoCamera).
export function shifted(frame, along) {
  return { ...frame, position: vec3.add(frame.position, scale(frame.right, along)) };
}

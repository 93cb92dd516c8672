"""Image error measures of a gallery still against a reference (Mitsuba 3's path tracer):
relMSE (photon.relmse), PSNR over the reference's peak, and the mean of NVIDIA's HDR-FLIP
(OpenImageIO's ImageBufAlgo.FLIP_diff, ACES tone mapping, its default 67 pixels per degree)."""

from __future__ import annotations

import math

import numpy as np

from ..photon import relmse

__all__ = ["flip", "image_errors", "psnr", "write_comparison"]


def psnr(image: np.ndarray, reference: np.ndarray) -> float:
    """10 log10(peak^2 / MSE) with peak = the reference's largest value (linear radiance)."""
    image, reference = np.asarray(image, np.float64), np.asarray(reference, np.float64)
    mse = float(np.mean((image - reference) ** 2))
    peak = float(reference.max())
    return math.inf if mse == 0 else 10 * math.log10(peak * peak / mse)


def flip(image: np.ndarray, reference: np.ndarray) -> float:
    """Mean HDR-FLIP error in [0, 1] (0 = identical), through OpenImageIO."""
    import OpenImageIO as oiio

    def buf(a):
        a = np.ascontiguousarray(a, np.float32)
        b = oiio.ImageBuf(oiio.ImageSpec(a.shape[1], a.shape[0], 3, oiio.FLOAT))
        b.set_pixels(oiio.ROI(), a)
        return b

    diff = oiio.ImageBufAlgo.FLIP_diff(buf(reference), buf(image))
    return float(np.asarray(diff.get_pixels(oiio.FLOAT))[..., 0].mean())


def write_comparison(path, images: list, display) -> None:
    """Linear stills of one view (ours, Mitsuba's reference, ...) side by side as one PNG,
    each through the same camera response (a display_mapping.Display: the room's exposure and
    tone curve, as `render` and the walk show them), 4 dark pixels apart."""
    from ..outputs import write_image

    tiles = [display.srgb8(np.asarray(im, np.float32)) for im in images]
    gap = np.full((tiles[0].shape[0], 4, 3), 16, np.uint8)
    row = [x for t in tiles for x in (t, gap)][:-1]
    write_image(path, np.concatenate(row, axis=1))


def image_errors(image: np.ndarray, reference: np.ndarray) -> dict:
    """{'relmse', 'psnr', 'flip'} of image against reference (both (H, W, 3) linear RGB)."""
    return {"relmse": relmse(image, reference), "psnr": psnr(image, reference), "flip": flip(image, reference)}

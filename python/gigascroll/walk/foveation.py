"""Fixed foveation of the gallery walk's eyes (issue 14 §1, the seed's named future work).

Headsets without eye tracking foveate about the lens centre; so does this. Per eye:

- the fovea, a centred rectangle `fovea_deg` wide and high (the same angle on both axes), is
  traced at full density by a *crop camera*: the eye's pose, the tangents of its half angles
  scaled by the crop's share of the pixels, and only those pixels. A centred crop of a pinhole
  image at the same pixel pitch is exactly that camera, so its pixels are the eye's pixels
  (to rounding) and its levels of detail are the eye's;
- the whole eye is traced at 1/`factor` density per axis by a *periphery camera* (same pose,
  ceil(W / factor) x ceil(H / factor) pixels at `factor` times the pitch), whose image is
  upsampled bilinearly to the eye's pixels; its pixels' footprints are `factor` times wider,
  so both its display samples and its feedback requests are log2(factor) levels coarser (one
  level at the default factor 2): the periphery asks for, and shows, less detail;
- inside the fovea's rectangle a blend band (`blend` of its half size) ramps from the
  periphery's image at the edge to the fovea's (smoothstep per axis, multiplied), so no seam
  shows; inside the band the frame is the fovea's image alone.

Both eyes are rendered as two stereo pairs (the fovea pair, the periphery pair), each with
the right eye reusing the left eye's hits, so the right eye keeps its saving. The feedback
pass runs on the same cameras at the eyes' 1/8 per axis of each camera's own pixels.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .. import views as v

__all__ = ["Foveation", "FoveaLayout", "FoveatedDisplay", "crop_camera", "upsample_to"]

_STAT_KEYS = ("rays_seconds", "reuse_seconds", "vt_seconds", "shade_seconds", "pixels", "hits",
              "traced", "reused", "painting_pixels")


def crop_camera(camera, width: int, height: int):
    """The centred width x height crop of `camera`'s image at the same pixel pitch: same pose,
    half-angle tangents scaled by the crop's share. (camera.width - width) and
    (camera.height - height) must be even, so the crop's pixels are whole pixels of the eye."""
    w, h = int(width), int(height)
    if not (0 < w <= camera.width and 0 < h <= camera.height):
        raise ValueError(f"a crop of {w} x {h} does not fit the {camera.width} x "
                         f"{camera.height} camera")
    if (camera.width - w) % 2 or (camera.height - h) % 2:
        raise ValueError("a centred crop must leave an even number of pixels on each axis")
    return v.Camera(tuple(camera.position), tuple(camera.forward), tuple(camera.up),
                    camera.tan_half_x * w / camera.width, camera.tan_half_y * h / camera.height,
                    w, h)


def _scaled_camera(camera, factor: int):
    """The periphery camera: `factor` times the pixel pitch, covering at least the eye."""
    w, h = -(-camera.width // factor), -(-camera.height // factor)
    return v.Camera(tuple(camera.position), tuple(camera.forward), tuple(camera.up),
                    camera.tan_half_x * w * factor / camera.width,
                    camera.tan_half_y * h * factor / camera.height, w, h)


def _bilinear_taps(n_out: int, n_in: int, factor: int):
    """Per output pixel of an axis: the two input pixels and the second one's weight, for an
    input `factor` times coarser whose centre is the output's centre."""
    u = (np.arange(n_out) + 0.5 - n_out / 2) / factor + n_in / 2 - 0.5
    i0 = np.floor(u).astype(np.int64)
    f = (u - i0).astype(np.float32)
    return np.clip(i0, 0, n_in - 1), np.clip(i0 + 1, 0, n_in - 1), f


def upsample_to(low: np.ndarray, width: int, height: int, factor: int) -> np.ndarray:
    """Bilinear upsampling of the periphery camera's image (h x w x 3, `factor` times the
    pitch, centred) to the eye's width x height pixels (separable: rows, then columns)."""
    ya, yb, fy = _bilinear_taps(height, low.shape[0], factor)
    xa, xb, fx = _bilinear_taps(width, low.shape[1], factor)
    fy = fy[:, None, None]
    rows = low[ya] * (1 - fy) + low[yb] * fy
    fx = fx[None, :, None]
    return rows[:, xa] * (1 - fx) + rows[:, xb] * fx


def _ramp(n: int, band: float) -> np.ndarray:
    """Blend weight along one axis of the fovea: 0 at its edge, smoothstep up to 1 at `band`
    pixels in (from the pixel centre), 1 beyond."""
    x = np.arange(n) + 0.5
    d = np.minimum(x, n - x)
    if band <= 0:
        return np.ones(n, np.float32)
    t = np.clip(d / band, 0.0, 1.0)
    return (t * t * (3 - 2 * t)).astype(np.float32)


@dataclass(frozen=True)
class FoveaLayout:
    """Where the fovea lies in one eye and the two cameras that trace it."""
    width: int
    height: int
    x0: int
    y0: int
    fovea_width: int
    fovea_height: int
    factor: int
    fovea: object       # Camera: the crop
    periphery: object   # Camera: the whole eye at 1/factor density
    weight_x: np.ndarray  # per fovea column: the fovea image's blend weight along x
    weight_y: np.ndarray  # per fovea row

    @property
    def weight(self) -> np.ndarray:
        """fovea_height x fovea_width: the fovea image's blend weight (1: the fovea alone)."""
        return np.outer(self.weight_y, self.weight_x)

    @property
    def traced_pixels(self) -> int:
        """Primary rays one eye traces foveated (the unfoveated eye: width x height)."""
        return (self.fovea_width * self.fovea_height
                + self.periphery.width * self.periphery.height)

    def masks(self) -> dict[str, np.ndarray]:
        """Boolean masks of the eye's pixels: the fovea (the fovea's image alone), the blend
        band and the periphery (outside the fovea's rectangle)."""
        inner = np.zeros((self.height, self.width), bool)
        band = np.zeros_like(inner)
        sl = (slice(self.y0, self.y0 + self.fovea_height),
              slice(self.x0, self.x0 + self.fovea_width))
        inner[sl] = self.weight == 1.0
        band[sl] = self.weight < 1.0
        return {"fovea": inner, "band": band, "periphery": ~(inner | band)}

    def composite(self, fovea_img: np.ndarray, periphery_img: np.ndarray,
                  threads: int = 0) -> np.ndarray:
        """The eye's frame: the periphery upsampled, the fovea blended in over its rectangle
        (one multithreaded pass in the core: sampling/foveation.h)."""
        from .. import _core
        return _core._composite_foveated(
            np.ascontiguousarray(periphery_img, np.float32),
            np.ascontiguousarray(fovea_img, np.float32), self.weight_x, self.weight_y,
            self.x0, self.y0, self.factor, self.width, self.height, threads)

    def composite_reference(self, fovea_img: np.ndarray, periphery_img: np.ndarray) -> np.ndarray:
        """composite() in numpy (the reference the tests hold the core to)."""
        out = upsample_to(periphery_img, self.width, self.height, self.factor)
        ys = slice(self.y0, self.y0 + self.fovea_height)
        xs = slice(self.x0, self.x0 + self.fovea_width)
        w = self.weight[:, :, None]
        out[ys, xs] = fovea_img * w + out[ys, xs] * (1 - w)
        return out


@dataclass(frozen=True)
class Foveation:
    """Fixed foveation: a centred fovea `fovea_deg` wide and high traced at full density, the
    rest at 1/`factor` density per axis (requested `log2(factor)` levels coarser), a blend
    band `blend` of the fovea's half size wide inside the fovea."""
    fovea_deg: float = 30.0
    factor: int = 2
    blend: float = 0.25

    def __post_init__(self):
        d = self.fovea_deg
        if isinstance(d, bool) or not isinstance(d, (int, float, np.floating, np.integer)) \
                or not math.isfinite(d) or not 0 < d < 180:
            raise ValueError(f"the fovea angle must be a number of degrees in (0, 180), got {d!r}")
        k = self.factor
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 2 <= k <= 16:
            raise ValueError(f"the periphery's density factor must be an integer in [2, 16], "
                             f"got {k!r}")
        b = self.blend
        if isinstance(b, bool) or not isinstance(b, (int, float, np.floating)) \
                or not math.isfinite(b) or not 0 <= b < 1:
            raise ValueError(f"the blend band must be a fraction in [0, 1), got {b!r}")

    def layout(self, camera) -> FoveaLayout:
        """The fovea and periphery cameras of one eye. The fovea must be narrower than the
        eye's field of view on both axes."""
        t = math.tan(math.radians(self.fovea_deg) / 2)
        W, H = int(camera.width), int(camera.height)
        if not (t < camera.tan_half_x and t < camera.tan_half_y):
            fov_x = math.degrees(2 * math.atan(camera.tan_half_x))
            fov_y = math.degrees(2 * math.atan(camera.tan_half_y))
            raise ValueError(f"the fovea ({self.fovea_deg:g} degrees) must be narrower than "
                             f"the eye's field of view ({fov_x:.1f} x {fov_y:.1f} degrees)")

        def extent(n, tan_half):
            e = int(round(n * t / tan_half))
            e -= (n - e) % 2          # a centred crop of whole pixels
            return max(e, 2 - n % 2)
        fw, fh = extent(W, camera.tan_half_x), extent(H, camera.tan_half_y)
        band = self.blend * min(fw, fh) / 2
        return FoveaLayout(W, H, (W - fw) // 2, (H - fh) // 2, fw, fh, int(self.factor),
                           crop_camera(camera, fw, fh), _scaled_camera(camera, self.factor),
                           _ramp(fw, band), _ramp(fh, band))

    def feedback_views(self, views, feedback_scale: int = 8) -> list:
        """The feedback views of a frame foveated: each eye (the first two views) replaced by
        its fovea and periphery cameras, each at 1/feedback_scale of its own pixels per
        axis; other views (the magnifier) kept."""
        out = []
        for i, view in enumerate(views):
            if i >= 2:
                out.append(view)
                continue
            lay = self.layout(view[0])
            for cam in (lay.fovea, lay.periphery):
                out.append((cam, max(1, cam.width // feedback_scale),
                            max(1, cam.height // feedback_scale)))
        return out


class FoveatedDisplay:
    """The display pass of both eyes foveated, through a FrameSource: the fovea pair and the
    periphery pair each rendered as a stereo pair (right eye reusing the left eye's hits),
    then composited per eye. left_stats / right_stats: the two passes' sums, as the
    DisplayPass gives them, plus `composite_seconds` (upsampling and blending), which
    total_seconds includes."""

    def __init__(self, foveation: Foveation):
        from .. import _core
        self.foveation = foveation
        self.passes = (_core.DisplayPass(), _core.DisplayPass())
        self.layout = None
        self.left_stats = self.right_stats = {}

    def display_stereo(self, source, vt, left, right, reuse: bool = True, threads: int = 0):
        ll, rl = self.foveation.layout(left), self.foveation.layout(right)
        fov_pass, per_pass = self.passes
        lf, rf = source.display_stereo(fov_pass, vt, ll.fovea, rl.fovea, reuse, threads)
        lp, rp = source.display_stereo(per_pass, vt, ll.periphery, rl.periphery, reuse, threads)
        stats = []
        images = []
        for eye, lay, f_img, p_img in ((0, ll, lf, lp), (1, rl, rf, rp)):
            t0 = time.perf_counter()
            images.append(lay.composite(f_img, p_img, threads))
            s = {k: 0.0 if k.endswith("_seconds") else 0 for k in _STAT_KEYS}
            for d in self.passes:
                es = d.left_stats if eye == 0 else d.right_stats
                for k in _STAT_KEYS:
                    s[k] += es[k]
            s["composite_seconds"] = time.perf_counter() - t0
            s["total_seconds"] = sum(s[k] for k in ("rays_seconds", "reuse_seconds",
                                                    "vt_seconds", "shade_seconds",
                                                    "composite_seconds"))
            stats.append(s)
        self.layout = ll
        self.left_stats, self.right_stats = stats
        return images[0], images[1]

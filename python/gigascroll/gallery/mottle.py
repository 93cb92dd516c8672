"""The mottle of baked light: what the eye sees of the light's error, per kind of surface.

An image-average error (relMSE) hides structure of a few percent at the scale of the photon
gather's radius (centimetres to decimetres): cloud-like patches on a flat wall or a flat-colour
painting. This measure compares an image of ours with a high-spp reference (Mitsuba 3) after a
small Gaussian blur that removes the reference's own pixel noise, each flat piece of surface
blurred on its own (normalised convolution inside its mask, so that neither an edge between
surfaces nor a painting's border mixes into its neighbour), and reports the RMS of the relative
error of the blurred luminance on walls, floor, ceiling, paintings and other surfaces
separately.

With paintings of one flat colour (as `gigascroll bench mottle` builds them) radiance is albedo
x irradiance / pi with the same albedo in both images, so the relative radiance error is the
relative irradiance error: the painting's own texture does not count.

The reference's own remaining noise after the blur is estimated from its pixel-scale residual
(the reference minus its blur) times the blur's noise gain sqrt(sum of squared weights): the
floor below which this measure cannot see.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CLASSES", "gaussian_blur", "masked_blur", "surface_segments", "mottle", "luminance"]

# The kinds of surface reported (a pixel of none of these is not measured).
CLASSES = ("walls", "floor", "ceiling", "paintings", "other")
_REC709 = np.array([0.2126, 0.7152, 0.0722])


def luminance(rgb: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance of linear RGB (..., 3), float64."""
    return np.asarray(rgb, np.float64) @ _REC709


def _kernel(sigma: float) -> np.ndarray:
    r = max(1, int(np.ceil(3 * sigma)))
    x = np.arange(-r, r + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / sigma) ** 2)
    return k / k.sum()


def gaussian_blur(image: np.ndarray, sigma: float) -> np.ndarray:
    """Separable Gaussian blur of a 2D array (zero outside), float64."""
    if not sigma > 0:
        raise ValueError(f"sigma must be positive, got {sigma!r}")
    k = _kernel(float(sigma))
    a = np.asarray(image, np.float64)
    a = np.apply_along_axis(np.convolve, 0, a, k, mode="same")
    return np.apply_along_axis(np.convolve, 1, a, k, mode="same")


def masked_blur(image: np.ndarray, mask: np.ndarray, sigma: float) -> np.ndarray:
    """Normalised convolution: the Gaussian mean of `image` over the pixels of `mask` only
    (NaN outside the mask)."""
    m = np.asarray(mask, bool)
    x = np.where(m, np.asarray(image, np.float64), 0.0)
    num, den = gaussian_blur(x, sigma), gaussian_blur(m.astype(np.float64), sigma)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(m & (den > 1e-12), num / den, np.nan)


def noise_gain(sigma: float) -> float:
    """How much a 2D Gaussian blur of `sigma` pixels scales white noise's RMS."""
    k = _kernel(float(sigma))
    return float((k ** 2).sum())  # the 2D kernel is the outer product: sqrt((sum k^2)^2)


def _triangles(spec):
    """All room triangles: (a, b, c) vertices (T, 3) each, their surface's index."""
    a, b, c, which = [], [], [], []
    for i, s in enumerate(spec.surfaces):
        v, t = np.asarray(s.vertices, np.float64), np.asarray(s.triangles, np.int64)
        a.append(v[t[:, 0]]), b.append(v[t[:, 1]]), c.append(v[t[:, 2]]), which.append(np.full(len(t), i))
    return np.concatenate(a), np.concatenate(b), np.concatenate(c), np.concatenate(which)


def _plane_classes(spec, n: np.ndarray, d: np.ndarray, which: np.ndarray) -> list[str]:
    """Each triangle's class: walls, floor and ceiling are the room's support planes (every
    vertex of the room on one side), vertical or horizontal; emitters and the rest are other."""
    verts = np.concatenate([np.asarray(s.vertices, np.float64) for s in spec.surfaces])
    size = float(np.ptp(verts, axis=0).max())
    tol = 1e-4 * size + 1e-6
    out = []
    for nt, dt, w in zip(n, d, which):
        side = verts @ nt - dt
        support = side.min() > -tol or side.max() < tol
        emits = max(spec.surfaces[w].emission) > 0
        if emits or not support:
            out.append("other")
        elif abs(nt[1]) < 0.1:
            out.append("walls")
        elif abs(nt[1]) > 0.9:
            # the floor: all of the room above it
            above = (side.min() > -tol) == (nt[1] > 0)
            out.append("floor" if above else "ceiling")
        else:
            out.append("other")
    return out


def surface_segments(spec, position: np.ndarray, slot: np.ndarray, chunk: int = 1 << 14):
    """Per pixel of a hits pass: (segment id (H, W) int, -1 where nothing is hit or the
    surface is not found; {segment id: class}). A painting slot is one segment; room triangles
    lying in one plane are one segment."""
    a, b, c, which = _triangles(spec)
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    n = n / np.maximum(area2, 1e-30)[:, None]
    d = np.einsum("ij,ij->i", n, a)
    classes = _plane_classes(spec, n, d, which)
    # one id per plane (up to the sign of the normal) and class
    canon = np.sign(n[np.arange(len(n)), (np.abs(n) > 1e-6).argmax(1)])[:, None]
    key = np.round(np.concatenate([n * canon, d[:, None] * canon], 1), 3)
    plane_ids = {}
    tri_seg = np.array([plane_ids.setdefault((tuple(k), cl), len(plane_ids)) for k, cl in zip(key, classes)])
    seg_class = {v: cl for (k, cl), v in plane_ids.items()}
    slots = np.asarray(slot)
    n_slots = int(slots.max()) + 1 if slots.size else 0
    base = len(plane_ids)
    for k in range(max(0, n_slots)):
        seg_class[base + k] = "paintings"
    p = np.asarray(position, np.float64).reshape(-1, 3)
    out = np.full(len(p), -1, np.int64)
    flat_slot = slots.reshape(-1)
    out[flat_slot >= 0] = base + flat_slot[flat_slot >= 0]
    size = float(np.ptp(np.concatenate([a, b, c]), axis=0).max())
    tol = 1e-4 * size + 1e-5
    todo = np.flatnonzero((flat_slot < 0) & np.isfinite(p).all(1))
    e1, e2 = b - a, c - a
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((e1, e1), (e1, e2), (e2, e2)))
    den = d00 * d11 - d01 ** 2
    for start in range(0, len(todo), chunk):
        idx = todo[start:start + chunk]
        q = p[idx][:, None, :] - a[None]                     # (m, T, 3)
        dist = np.abs(np.einsum("mtk,tk->mt", q, n))
        d20, d21 = np.einsum("mtk,tk->mt", q, e1), np.einsum("mtk,tk->mt", q, e2)
        with np.errstate(invalid="ignore", divide="ignore"):
            v = (d11 * d20 - d01 * d21) / den
            w = (d00 * d21 - d01 * d20) / den
        eps = 1e-4
        inside = (dist < tol) & (v > -eps) & (w > -eps) & (v + w < 1 + eps)
        dist = np.where(inside, dist, np.inf)
        best = dist.argmin(1)
        found = np.isfinite(dist[np.arange(len(idx)), best])
        out[idx[found]] = tri_seg[best[found]]
    return out.reshape(np.asarray(slot).shape), seg_class


def pool_segments(segments: np.ndarray, k: int, margin: int = 1) -> np.ndarray:
    """Segments of a k x k supersampled hits pass to pixels: a pixel's segment where all its
    k^2 samples agree and every pixel within `margin` of it (inside the image) has the same
    segment, else -1.

    The first rule leaves out pixels whose samples mix surfaces; the margin, pixels that only
    look pure. A reference pixel is the mean over the pixel's whole box, which reaches up to
    1 / (2k) of a pixel beyond our outermost samples, and there a surface's edge shows what
    the light does at the millimetre scale (a painting 1 mm above a table: the contact shadow
    in the gap, seen at a grazing angle). In the hall seen from above its table, the edge row
    of a 2.7 cm painting was 12% darker in the reference than in a 15 x 15-sample image of
    ours, and the painting's interior rows agreed within 0.2%: that is geometry, not the
    light's mottle."""
    h, w = segments.shape[0] // k, segments.shape[1] // k
    blocks = segments[:h * k, :w * k].reshape(h, k, w, k).transpose(0, 2, 1, 3).reshape(h, w, k * k)
    first = blocks[..., 0]
    pooled = np.where((blocks == first[..., None]).all(-1), first, -1)
    if margin <= 0:
        return pooled
    padded = np.pad(pooled, margin, mode="edge")  # the image's border is no edge
    same = np.ones(pooled.shape, bool)
    for dy in range(-margin, margin + 1):
        for dx in range(-margin, margin + 1):
            same &= padded[margin + dy:margin + dy + h, margin + dx:margin + dx + w] == pooled
    return np.where(same, pooled, -1)


def mottle(image: np.ndarray, reference: np.ndarray, segments: np.ndarray, seg_class: dict,
           sigma: float = 2.0) -> dict:
    """Per class: RMS, mean, 1st and 99th percentile of the relative error of the blurred
    luminance (blurred within each segment), the pixels measured, and the reference's own
    noise left after the blur (estimated). Pixels whose blurred reference is below 1e-3 of the
    image's 99th percentile are not measured (relative error of darkness)."""
    y, yr = luminance(image), luminance(reference)
    by, byr = np.full(y.shape, np.nan), np.full(y.shape, np.nan)
    resid = np.full(y.shape, np.nan)
    for s in np.unique(segments[segments >= 0]):
        m = segments == s
        by[m] = masked_blur(y, m, sigma)[m]
        blurred_ref = masked_blur(yr, m, sigma)
        byr[m] = blurred_ref[m]
        resid[m] = (yr - blurred_ref)[m]
    floor = 1e-3 * np.nanpercentile(yr[segments >= 0], 99) if (segments >= 0).any() else 0.0
    gain = noise_gain(sigma)
    out = {"sigma_px": float(sigma)}
    for cl in CLASSES:
        ids = [s for s, c in seg_class.items() if c == cl]
        m = np.isin(segments, ids) & np.isfinite(byr) & (byr > floor)
        if not m.any():
            out[cl] = None
            continue
        rel = by[m] / byr[m] - 1
        noise = float(np.sqrt(np.mean((resid[m] / byr[m]) ** 2)) * gain)
        out[cl] = {"rms": float(np.sqrt(np.mean(rel ** 2))), "mean": float(rel.mean()),
                   "rms_about_mean": float(rel.std()), "p1": float(np.percentile(rel, 1)),
                   "p99": float(np.percentile(rel, 99)), "pixels": int(m.sum()),
                   "reference_noise": noise}
    return out

"""The illuminance on each painting, in lux, as the gallery's light gives it: the figures
conservators light by.

Illuminance is the irradiance on the painting's visible side, computed by the core where the
renders compute it (the baked lattice, or lighting "full": direct light and photon gather at
each point), at the cell centres of a grid over the slot (slot_grid). The core evaluates it
through `Gallery.render_display(..., hits=True)` with a camera 1 cm in front of the painting,
looking straight at it, whose pixels are exactly those cell centres (a pinhole camera
perpendicular to a plane maps its pixel grid onto a uniform grid there). A point that camera
does not see on the painting (something within 1 cm in front of it) is NaN.

Lux: irradiance E (W / m^2 per linear sRGB channel) -> 683 lm / W x (0.2126 E_r + 0.7152 E_g +
0.0722 E_b), the photometric weighting of linear sRGB (room/light_colour.py); for white
light this is the project's "lux equivalent" (room/builtin.py).
"""

from __future__ import annotations

import math

import numpy as np

from .._core import Camera
from .conservation import CategoryLimits, annual_exposure, check_exposure
from ..room.light_colour import luminance
from ..room.lights import LUMENS_PER_WATT, light_colour, panels_irradiance
from ..room.slot_grid import grid_shape, slot_front, slot_points

__all__ = ["CAMERA_DISTANCE_M", "painting_lux", "direct_lux", "lux_stats", "painting_figures"]

CAMERA_DISTANCE_M = 0.01


def painting_lux(gallery, vt, slot: int, samples: int = 128, lighting: str = "baked",
                 threads: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(lux (rows, columns), positions (rows, columns, 3)) on painting slot `slot` of the
    gallery, at slot_points(slot, samples); NaN where the painting is not seen."""
    spec_slot = gallery.spec.paintings[slot]
    cols, rows = grid_shape(spec_slot, samples)
    front = slot_front(spec_slot)
    o, u, v = (np.asarray(x, np.float64) for x in (spec_slot.origin, spec_slot.u_axis,
                                                    spec_slot.v_axis))
    w, h = float(spec_slot.width_m), float(spec_slot.height_m)
    centre = o + 0.5 * w * u + 0.5 * h * v
    d = CAMERA_DISTANCE_M
    # forward x up = right: (-front) x (-v) = u, so image x runs along u and image y along v.
    camera = Camera(tuple(centre + d * front), tuple(-front), tuple(-v), 0.5 * w / d, 0.5 * h / d,
                    cols, rows)
    _, hits = gallery.render_display(camera, vt, lighting=lighting, hits=True, threads=threads)
    lux = LUMENS_PER_WATT * luminance(hits["irradiance"].astype(np.float64))
    lux[hits["slot"] != slot] = np.nan
    return lux, hits["position"].astype(np.float64)


def direct_lux(room, slot: int, samples: int = 128) -> np.ndarray | None:
    """The direct illuminance (lux, (rows, columns)) the room's light specs give slot `slot`'s
    grid with nothing in between (Lambert's polygon formula), or None when the room's emitters
    were not all made from light specs."""
    lights = [light for light in room.lights if light.details]
    emitters = sum(1 for s in room.surfaces if max(s.emission) > 0)
    if not lights or len(lights) != emitters:
        return None
    s = room.paintings[slot]
    points = slot_points(s, samples)
    total = np.zeros(points.shape[:2])
    for light in lights:
        unit = panels_irradiance(points, slot_front(s), light.panels)
        y = light.details["radiance"] * float(luminance(light_colour(light)))
        total += (unit * y).reshape(total.shape)
    return LUMENS_PER_WATT * total


def lux_stats(lux: np.ndarray) -> dict:
    """min, mean and max lux over the points seen, uniformity (min / mean) and the share of
    points seen; None figures when none is."""
    seen = np.isfinite(lux)
    if not seen.any():
        return {"min_lux": None, "mean_lux": None, "max_lux": None, "uniformity": None,
                "seen_share": 0.0}
    x = lux[seen]
    mean = float(x.mean())
    return {"min_lux": float(x.min()), "mean_lux": mean, "max_lux": float(x.max()),
            "uniformity": float(x.min() / mean) if mean > 0 else None,
            "seen_share": float(seen.mean())}


def painting_figures(lux: np.ndarray, limits: CategoryLimits, hours_per_day: float,
                     days_per_year: float) -> dict:
    """lux_stats with the yearly exposure (lux hours at the mean and at the brightest point
    for these opening hours), the hours a year the category's dose allows at the brightest
    point, and the category's warnings."""
    f = lux_stats(lux)
    hours = annual_exposure(1.0, hours_per_day, days_per_year)
    if f["mean_lux"] is None:
        f.update(annual_lux_hours_mean=None, annual_lux_hours_max=None, max_hours_per_year=None,
                 warnings=["the painting is not visible from its front: no figures"])
        return f
    f["annual_lux_hours_mean"] = f["mean_lux"] * hours
    f["annual_lux_hours_max"] = f["max_lux"] * hours
    # How long a year the painting may be shown under this light (its brightest point within
    # the category's yearly dose): what decides a rotation.
    f["max_hours_per_year"] = (limits.lux_hours / f["max_lux"]
                               if limits.lux_hours is not None and f["max_lux"] > 0 else None)
    f["warnings"] = check_exposure(limits, f["max_lux"], f["annual_lux_hours_max"])
    if not math.isfinite(f["max_lux"]):
        f["warnings"].append("the illuminance is not finite")
    return f

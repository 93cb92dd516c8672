"""One knob for the gallery's light: a quality level or a time budget to photon pass and bake
settings, by a rule that reads only the room.

    settings = light_settings(spec, quality="final")        # or budget=0.5 (seconds)
    stats = apply_settings(gallery, settings, vt)           # light() then bake()

A user says how good (`--quality draft|preview|final`) or how fast (`--light-budget SECONDS`);
the photon count, the bake's spacing, its emitter samples, its final gather and gather stride
and the still's rays per pixel follow from a ladder of steps (`STEPS`), each scaled to the room:

- spacing: the room's diagonal / n. A room scaled by s (light positions included) has the same
  light field scaled by s, so the same n and the same photon count give the same relative
  error: the rule is scale-free.
- photons: the step's count times the room's surface area over its diagonal squared, relative
  to that of the rooms the steps were measured on (1.27): a room with more surface within the
  same bounds (partitions, plinths) gets as many photons per square metre. Clamped to
  [1/2, 8] of the step's count, a power of two.
- emitter samples: the step's count times one more for every two emitting surfaces past two
  (up to 4x): each lattice point splits its samples among the lights.

The steps were measured (docs/light.md, "One knob") on the built-in `scroll` and `hall` rooms
against Mitsuba 3 references: the error target of each level (`ERROR_TARGETS`) is the RMS
relative error of the luminance of flat surfaces after a 2-pixel blur (gallery.mottle's
measure) on walls and floors. The choice is fixed in this module; no reference is consulted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["LightSettings", "QUALITY_LEVELS", "DEFAULT_QUALITY", "ERROR_TARGETS", "STEPS",
           "RoomMeasures", "room_measures", "light_settings", "apply_settings", "check_quality",
           "check_budget", "predicted_seconds", "still_spp", "MAX_STILL_SAMPLES"]

QUALITY_LEVELS = ("draft", "preview", "final")
DEFAULT_QUALITY = "final"
# The stated target of each level: RMS relative error of the blurred luminance on walls and
# floors against a converged reference (paintings at final: 0.5%).
ERROR_TARGETS = {"draft": 0.08, "preview": 0.06, "final": 0.01}
# The rooms the steps were measured on: area / diagonal^2 (hall 1.58, scroll 0.96).
FITTED_AREA_RATIO = 1.27
MAX_BUDGET_S = 86400.0


@dataclass(frozen=True)
class Step:
    """One step of the ladder for a room like the fitted ones: log2 photons, spacing diag / n,
    emitter samples, final gather rays, gather stride, the still's rays per pixel, and whether
    the final gather runs on the gathers' sub-lattice only (bake(sparse_final_gather))."""

    photons_log2: int
    diagonal_over: int
    light_samples: int
    final_gather: int
    gather_stride: int
    spp: int
    sparse: bool = False


# From cheapest to finest; the levels are steps 0, 2 and 4. Budgets pick any step. From step 3
# the final gather runs on the gathers' sub-lattice (every other point each way) with more rays
# a point: the same mottle at 0.6x the bake (docs/light.md). The still's rays per pixel grow
# with the light's accuracy: at the finer steps the hall's error against Mitsuba was half
# aliasing at 3 x 3 (relMSE 4.7e-6 at 9 rays a pixel, 2.3e-6 at 49, the same bake).
STEPS = (Step(10, 25, 1, 4, 1, 9),      # draft
         Step(12, 50, 4, 4, 1, 9),
         Step(14, 50, 4, 16, 1, 25),    # preview
         Step(16, 100, 16, 36, 2, 49, sparse=True),
         Step(19, 200, 16, 36, 2, 49, sparse=True),   # final: issue 40's mottle goal
         Step(20, 250, 16, 64, 2, 81, sparse=True))
LEVEL_STEPS = {"draft": 0, "preview": 2, "final": 4}


@dataclass(frozen=True)
class LightSettings:
    """What Gallery.light and Gallery.bake are given, and the still's rays per pixel. `level`:
    the quality level or "budget" (then `budget_s`); `step`: the ladder step."""

    level: str
    step: int
    photons: int
    spacing: float
    light_samples: int
    final_gather: int
    gather_stride: int
    spp: int
    budget_s: float | None = None
    sparse_final_gather: bool = False

    def light_options(self) -> dict:
        return {"photons": self.photons, "light_samples": self.light_samples}

    def bake_options(self) -> dict:
        return {"spacing": self.spacing, "light_samples": self.light_samples,
                "final_gather": self.final_gather, "gather_stride": self.gather_stride,
                "sparse_final_gather": self.sparse_final_gather}

    def describe(self) -> str:
        return (f"{self.level} (step {self.step}): 2^{int(math.log2(self.photons))} photons, "
                f"spacing {self.spacing:.3g} m, {self.light_samples} samples, final gather "
                f"{self.final_gather}{' (sparse)' if self.sparse_final_gather else ''}, gather stride "
                f"{self.gather_stride}, {self.spp} spp")


@dataclass(frozen=True)
class RoomMeasures:
    """What the rule reads of a room: its diagonal (m), surface area (m^2, both surfaces and
    painting slots), emitting surfaces, painting slots."""

    diagonal: float
    area: float
    lights: int
    paintings: int


def room_measures(spec) -> RoomMeasures:
    """The diagonal of the bounds of all vertices and slot corners, the total area, the number
    of emitting surfaces and of painting slots of a RoomSpec. ValueError for an empty room."""
    from ..room.spec import RoomSpec

    if not isinstance(spec, RoomSpec):
        raise ValueError(f"light settings need a RoomSpec, got {type(spec).__name__}")
    points, area, lights = [], 0.0, 0
    for s in spec.surfaces:
        v = np.asarray(s.vertices, np.float64).reshape(-1, 3)
        t = np.asarray(s.triangles, np.int64).reshape(-1, 3)
        if len(v) == 0 or len(t) == 0 or t.min() < 0 or t.max() >= len(v):
            continue
        points.append(v)
        area += 0.5 * float(np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]),
                                           axis=1).sum())
        lights += max(s.emission) > 0
    for p in spec.paintings:
        o, u, w = (np.asarray(x, np.float64) for x in (p.origin, p.u_axis, p.v_axis))
        points.append(np.array([o, o + p.width_m * u + p.height_m * w]))
        area += float(p.width_m * p.height_m)
    if not points:
        raise ValueError(f"room {spec.name!r} has no surfaces")
    allp = np.concatenate(points)
    diagonal = float(np.linalg.norm(allp.max(axis=0) - allp.min(axis=0)))
    if not (math.isfinite(diagonal) and diagonal > 0 and math.isfinite(area) and area > 0):
        raise ValueError(f"room {spec.name!r} has no extent (diagonal {diagonal}, area {area})")
    return RoomMeasures(diagonal, area, lights, len(spec.paintings))


def _scaled(step: Step, m: RoomMeasures, index: int, level: str, budget) -> LightSettings:
    ratio = min(8.0, max(0.5, m.area / m.diagonal ** 2 / FITTED_AREA_RATIO))
    photons = 1 << max(8, min(26, step.photons_log2 + round(math.log2(ratio))))
    samples = step.light_samples * min(4, max(1, math.ceil(m.lights / 2)))
    return LightSettings(level, index, photons, m.diagonal / step.diagonal_over, samples,
                         step.final_gather, step.gather_stride, step.spp, budget,
                         step.sparse and step.gather_stride > 1)


def check_quality(quality) -> str:
    if quality not in QUALITY_LEVELS:
        raise ValueError(f"quality must be one of {', '.join(QUALITY_LEVELS)}, got {quality!r}")
    return quality


def check_budget(budget) -> float:
    if isinstance(budget, bool) or not isinstance(budget, (int, float, np.integer, np.floating)) \
            or not math.isfinite(budget) or not 0 < budget <= MAX_BUDGET_S:
        raise ValueError(f"the light budget must be a number of seconds in (0, {MAX_BUDGET_S:g}], "
                         f"got {budget!r}")
    return float(budget)


# The cost model of predicted_seconds, seconds on 2 cores of the machine the steps were
# measured on: per photon traced and stored, per lattice point and per ray a point casts.
SECONDS_PER_PHOTON = 3.5e-7
SECONDS_PER_POINT_RAY = 1.0e-7


def predicted_seconds(s: LightSettings, m: RoomMeasures) -> float:
    """A rough light + bake time of the settings (the cost model above): photons, plus the
    lattice's points (about 2 area / spacing^2, both sides) times the rays each casts (its
    emitter samples, its final gather (sparse: on a stride^2-th of the points), its first
    pass's photon gather)."""
    points = 2 * m.area / s.spacing ** 2
    gathered = s.final_gather / (s.gather_stride ** 2 if s.sparse_final_gather else 1)
    rays = s.light_samples + 2 * gathered + 16 / s.gather_stride ** 2
    return SECONDS_PER_PHOTON * s.photons + SECONDS_PER_POINT_RAY * points * rays


# The most camera samples a still takes at a level's rays per pixel (render's limit).
MAX_STILL_SAMPLES = 1 << 26


def still_spp(spp: int, width: int, height: int) -> int:
    """A level's rays per pixel (a square) for a width x height still: the largest square up to
    `spp` whose samples stay within MAX_STILL_SAMPLES, at least 1 (a large still at a fine
    level: its light, not its antialiasing, is what the level promises)."""
    k = min(math.isqrt(spp), math.isqrt(max(1, MAX_STILL_SAMPLES // max(1, width * height))))
    return max(1, k) ** 2


def light_settings(spec, quality: str | None = None, budget: float | None = None) -> LightSettings:
    """The light's settings for a RoomSpec: those of a quality level (default DEFAULT_QUALITY),
    or, given `budget` (seconds of light + bake), of the finest step predicted to fit it (the
    cheapest step when none does). ValueError for both given, or a bad level or budget."""
    if quality is not None and budget is not None:
        raise ValueError("give a quality level or a light budget, not both")
    m = room_measures(spec)
    if budget is None:
        level = check_quality(DEFAULT_QUALITY if quality is None else quality)
        i = LEVEL_STEPS[level]
        return _scaled(STEPS[i], m, i, level, None)
    budget = check_budget(budget)
    chosen = _scaled(STEPS[0], m, 0, "budget", budget)
    for i, step in enumerate(STEPS[1:], 1):
        s = _scaled(step, m, i, "budget", budget)
        if predicted_seconds(s, m) <= budget:
            chosen = s
    return chosen


def apply_settings(gallery, settings: LightSettings, vt=None, threads: int = 0, seed: int = 0,
                   progress: bool = False, bake: bool = True, **overrides) -> dict:
    """Lights the gallery (and bakes, with `bake`) at `settings`; `overrides` replace fields of
    it (photons, spacing, light_samples, final_gather, gather_stride, sparse_final_gather;
    None: not given). vt:
    any VirtualTexture of the gallery's pack (None: a small one; the photons read the
    paintings' pinned coarse levels). Returns the gallery's stats."""
    given = {k: v for k, v in overrides.items() if v is not None}
    unknown = set(given) - {"photons", "spacing", "light_samples", "final_gather", "gather_stride",
                            "sparse_final_gather"}
    if unknown:
        raise ValueError(f"unknown light settings: {', '.join(sorted(unknown))}")
    if not isinstance(settings, LightSettings):
        raise ValueError(f"settings must be LightSettings, got {type(settings).__name__}")
    s = replace(settings, **given)
    if vt is None:
        from .. import runtime

        vt = runtime.VirtualTexture(gallery.pack, (30, 30))
    gallery.light(vt, threads=threads, seed=seed, **s.light_options())
    if bake:
        gallery.bake(threads=threads, progress=progress, **s.bake_options())
    return dict(gallery.stats)

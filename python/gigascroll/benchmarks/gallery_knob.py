"""`gigascroll bench gallery`'s curve along the quality knob (gallery/quality.py).

Where the front is the best of hundreds of configurations chosen afterwards against the
reference, the knob's curve is what a user gets: each step of the ladder (the three levels and
the steps a --light-budget picks between), scaled to the room by the rule, and the bake's
defaults (Gallery.light() and bake() as they are) as a marked point. Each is timed end to end
(photon pass + map + bake + still at the step's rays per pixel), its relMSE taken against the
cached reference, and Mitsuba's time to the same relMSE interpolated along its spp ladder; then
each point and the ladder points it is compared with are re-timed, interleaved, as the front's
targets are (gallery.retime), and the speedups are ratios of those medians.
"""

from __future__ import annotations

import math
import time

from ..gallery.quality import LEVEL_STEPS, STEPS, LightSettings, _scaled, room_measures


def knob_points(spec) -> list[LightSettings]:
    """The ladder's steps for this room (the levels among them), then the defaults: the
    photon pass and bake of Gallery.light() / bake() called without settings (read from
    their signatures; the spacing's default is the diagonal / 200), the still at the rays per
    pixel `render --room` uses without options (the default level's)."""
    import inspect

    from ..gallery import Gallery
    from ..gallery.quality import DEFAULT_QUALITY

    m = room_measures(spec)
    names = {i: level for level, i in LEVEL_STEPS.items()}
    points = [_scaled(step, m, i, names.get(i, f"step {i}"), None) for i, step in enumerate(STEPS)]
    light = {k: v.default for k, v in inspect.signature(Gallery.light).parameters.items()}
    bake = {k: v.default for k, v in inspect.signature(Gallery.bake).parameters.items()}
    spp = points[LEVEL_STEPS[DEFAULT_QUALITY]].spp
    defaults = LightSettings("defaults", -1, light["photons"], m.diagonal / 200, bake["light_samples"],
                             bake["final_gather"], bake["gather_stride"], spp, None,
                             bake["sparse_final_gather"] and bake["gather_stride"] > 1)
    return points + [defaults]


def measure_knob(gal, vt, spec, ref, ladder: list[dict], still, time_mitsuba, args, progress) -> list[dict]:
    """The knob's points for one room: settings, times, errors, Mitsuba's time to the same
    error, and the re-timed medians. still(gal, vt, ss) -> (image, seconds)."""
    from ..photon import relmse
    from .ladder_timing import _time_to_error, apply_repeats, retime, retime_plan

    def run(p: LightSettings):
        t0 = time.perf_counter()
        st = gal.light(vt, **p.light_options())
        t1 = time.perf_counter()
        bst = gal.bake(**p.bake_options())
        t2 = time.perf_counter()
        img, still_seconds = still(gal, vt, math.isqrt(p.spp))
        return img, st, bst, t1 - t0, t2 - t1, still_seconds

    rows = []
    for p in knob_points(spec):
        img, st, bst, light_s, bake_s, still_s = run(p)
        c = {"level": p.level, "step": p.step, "photons": p.photons, "spacing_m": p.spacing,
             "diagonal_over": round(math.dist(*gal.bounds) / p.spacing), "light_samples": p.light_samples,
             "final_gather": p.final_gather, "sparse_final_gather": p.sparse_final_gather,
             "gather_stride": p.gather_stride, "spp": p.spp,
             "bake_points": bst["bake_points"], "photon_seconds": st["photon_seconds"],
             "build_seconds": light_s - st["photon_seconds"], "bake_seconds": bake_s,
             "still_seconds": still_s, "total_seconds": light_s + bake_s + still_s,
             "relmse": relmse(img, ref), "settings": p}
        rows.append({"relmse": c["relmse"], "mitsuba_spp": None,
                     "mitsuba_seconds": _time_to_error(ladder, c["relmse"]), "ours": c,
                     "speedup": None, "speedup_at_least": None})
        progress()

    def time_ours(c):
        _img, _st, _bst, light_s, bake_s, still_s = run(c["settings"])
        progress()
        return light_s + bake_s + still_s

    n = sum(k for *_, k in retime_plan(rows, ladder, args.timing_repeats, args.cheap_repeats)[1])
    ours, mitsuba = retime(rows, ladder, time_ours, time_mitsuba, args.timing_repeats, args.cheap_repeats)
    out = []
    for row in apply_repeats(rows, ladder, ours, mitsuba):
        c = dict(row["ours"])
        c.pop("settings")
        row = {**row, "ours": c, "retimed_jobs": n}
        out.append(row)
    return out


def print_knob(name: str, rows: list[dict]) -> None:
    print(f"  {name}, along the quality knob (photon + map + bake + still; medians of the repeats):")
    for row in rows:
        c = row["ours"]
        m = row.get("mitsuba_median_seconds")
        ours = row.get("ours_median_seconds", c["total_seconds"])
        if m:
            lo, hi = row["speedup_range"]
            sp = f"{m:.3f} s / {ours:.4f} s = {row['speedup_median']:.1f}x ({lo:.1f}-{hi:.1f}x)"
        elif row.get("speedup_at_least_median"):
            sp = f"> {row['mitsuba_median_bound_seconds']:.2f} s / {ours:.4f} s = >{row['speedup_at_least_median']:.1f}x"
        else:
            sp = "-"
        print(f"    {c['level']:9s} 2^{int(math.log2(c['photons'])):<2d} diag/{c['diagonal_over']:<4d} "
              f"{c['light_samples']:3d} samples fg {c['final_gather']:3d}{'s' if c.get('sparse_final_gather') else ' '} "
              f"stride {c['gather_stride']} "
              f"{c['spp']} spp  relMSE {c['relmse']:.2e}  {sp}")


def plot_knob(ax, rows: list[dict]) -> None:
    """The knob's curve on the time-to-error axes, the levels named, the defaults marked."""
    pts = [(r.get("ours_median_seconds", r["ours"]["total_seconds"]), r["relmse"], r["ours"]["level"])
           for r in rows]
    steps = [p for p in pts if p[2] != "defaults"]
    ax.loglog([p[0] for p in steps], [p[1] for p in steps], "s-", color="C1", ms=5,
              label="quality knob (steps, medians)")
    for t, e, level in steps:
        if not level.startswith("step"):
            ax.annotate(level, (t, e), textcoords="offset points", xytext=(4, 4), fontsize=8, color="C1")
    for t, e, level in pts:
        if level == "defaults":
            ax.loglog([t], [e], "*", color="k", ms=11, label="Gallery.light/bake defaults")

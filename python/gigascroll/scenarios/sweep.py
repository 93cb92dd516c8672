"""`sweep`: VT-mobile-VR §5.5.1 / Fig. 12. A static camera 25 cm from one painting whose tile
total grows in five steps of 4096 tiles (the scroll's height and texel size, width cut to
the total); frame rate and determination cost of the basic method, Ma VT, LOD-texture's LOD
mapping and ours (hash). Both eyes, no magnifier."""

from __future__ import annotations

from .. import views as v
from ..experiments import pyplot, spec_of, width_for_tiles
from ..views.baselines import LodMapping
from . import common as c

METHODS = ("basic", "ma-vt", "lod-mapping", "hash")
HEIGHT = 1600  # 12.6 cm: the pack bytes stay at what the tile totals need


def painting_for(total: int, height: int = HEIGHT) -> v.PaintingSpec:
    """The narrowest painting of `height` whose pyramid has at least `total` tiles."""
    width = width_for_tiles(total, height)
    return spec_of(f"w{width}", width, height)


def run(opts: c.Options) -> dict:
    from tqdm import tqdm
    methods = c.check_methods(opts, METHODS, METHODS)
    totals = (256, 512, 768) if opts.quick else tuple(4096 * k for k in range(1, 6))
    frames = 20 if opts.quick else 90
    rep = c.Report("sweep", opts.out, "Scenario sweep: tile totals at a static camera "
                   "(VT-mobile-VR §5.5.1, Fig. 12)")
    res = rep.results
    res.update({"quick": opts.quick, "totals": list(totals), "rows": []})
    for total in tqdm(totals, desc="sweep: tile totals", unit="config"):
        spec = painting_for(total)
        ex = v.single_scroll(spec)
        pack = c.pattern_pack(opts, spec.width, spec.height)
        start = min(0.5, spec.width_m / 2)
        path = c.user_path(opts, v.scroll_path(distance=0.25, speed=0.0, duration=frames / 90,
                                               start_x=start, magnifier=False, exhibition=ex),
                           ex)
        for m in methods:
            lod = m == "lod-mapping"
            loop = c.frame_loop(opts, ex, pack, path, method=m, strategy="direct",
                                per_frame=1 << 20 if lod else None,
                                slots=c.lod_slots(ex, path) if lod else (30, 30),
                                magnifier=False)
            row = c.loop_row(loop, loop.run(), tiles=ex.tiles[0].total_tiles, method=m,
                             width=spec.width)
            if lod:
                row["lod_memory_mb"] = LodMapping(ex).memory_bytes(
                    path, 0, pack.tile_size ** 2 * 4) / 2 ** 20
            # Determination per frame = everything before the loads: feedback + processing.
            row["determination_ms"] = row["feedback_ms"] + row["processing_ms"]
            res["rows"].append(row)
    rows = res["rows"]
    checks = {
        # Every method ends with the static view fully sharp: each requests what it needs.
        "all_methods_end_sharp": all(r["records"][-1]["hit_rate"] == 1.0 for r in rows),
        # (the quick run's totals are too small to time reliably)
        "ma_vt_cost_grows_with_tiles": None if opts.quick else _grows(
            [r for r in rows if r["method"] == "ma-vt"]),
    }
    return rep.finish(checks, _report, methods)


def _grows(rows) -> bool | None:
    if len(rows) < 2:
        return None
    return rows[-1]["processing_ms"] > rows[0]["processing_ms"]


def _report(rep, res, methods):
    fig, axes = pyplot().subplots(1, 2, figsize=(10, 3.5))
    for m in methods:
        rows = [r for r in res["rows"] if r["method"] == m]
        axes[0].plot([r["tiles"] for r in rows], [r["fps_from_frame_time"] for r in rows], "o-",
                     label=m)
        axes[1].plot([r["tiles"] for r in rows], [r["determination_ms"] for r in rows], "o-",
                     label=m)
    axes[0].set_ylabel("fps (from frame time)")
    axes[1].set_ylabel("tile determination ms / frame")
    for ax in axes:
        ax.set_xlabel("tiles in the painting")
        ax.legend(fontsize=7)
    rep.figure(fig, "sweep.png", "frame rate and determination cost against the tile total")
    rep.table(["tiles", "method", "fps (paced)", "fps from frame time", "feedback ms",
               "processing ms", "display ms", "hit rate", "LOD memory MB"],
              [[r["tiles"], r["method"], r["fps"], r["fps_from_frame_time"], r["feedback_ms"],
                r["processing_ms"], r["display_ms"], f"{100 * r['hit_rate']:.1f}%",
                r.get("lod_memory_mb")] for r in res["rows"]])
    rep.text("VT-mobile-VR Fig. 12: ours and Unreal SVT stay at 90 fps, basic VT is slow, Ma VT "
             "falls as the tiles grow. For the baselines the rays of the display pass count "
             "as display, not feedback.\n")
    rep.checks(res["checks"])

"""`latency`: VT-mobile-VR §5.5.2. The camera 25 cm from the scroll moves at 0.5 m/s, then stops;
display latency (frames until every visible tile is resident at its requested level) of ours
(hash + direct loading) against CPU async processing (Unreal SVT), Ma VT and LOD-texture's LOD
mapping, all with the same loader."""

from __future__ import annotations

from .. import views as v
from ..views.baselines import LodMapping
from . import common as c

METHODS = ("hash", "cpu-async", "ma-vt", "lod-mapping", "flag-array", "basic")


def moving_then_stop(ex, start_x: float, duration: float, warm: int, stop: int) -> v.CameraPath:
    """Stand at the start for `warm` frames (the view becomes sharp: a steady state, as in
    the seed's measurement), move at 0.5 m/s for `duration` s, then stand still."""
    still = v.scroll_path(distance=0.25, speed=0.0, duration=warm / v.FPS, start_x=start_x,
                          exhibition=ex, magnifier=False)
    move = v.scroll_path(distance=0.25, speed=0.5, duration=duration, start_x=start_x,
                         exhibition=ex, magnifier=False, stop_frames=stop)
    return still.then(move)


def run(opts: c.Options) -> dict:
    from tqdm import tqdm
    methods = c.check_methods(opts, METHODS, METHODS[:4])
    ex, pack = c.scroll_room(opts)
    if opts.quick:
        path = moving_then_stop(ex, 0.3, 0.1, warm=20, stop=10)
    else:
        path = moving_then_stop(ex, 1.0, opts.duration or 2.0, warm=60, stop=90)
    path = c.user_path(opts, path, ex)
    rep = c.Report("latency", opts.out, "Scenario latency: display latency after a stop "
                   "(VT-mobile-VR §5.5.2)")
    res = rep.results
    res.update({"quick": opts.quick, "frames": len(path), "rows": []})
    for m in tqdm(methods, desc="latency: methods", unit="method"):
        lod = m == "lod-mapping"
        loop = c.frame_loop(opts, ex, pack, path, method=m, strategy="direct",
                            per_frame=1 << 20 if lod else None,
                            slots=c.lod_slots(ex, path, len(path) - 1) if lod else (30, 30),
                            magnifier=False)
        row = c.loop_row(loop, loop.run(), method=m)
        if lod:
            row["lod_memory_mb"] = LodMapping(ex).memory_bytes(
                path, len(path) - 1, pack.tile_size ** 2 * 4) / 2 ** 20
        res["rows"].append(row)
    by = {r["method"]: r for r in res["rows"]}
    # LOD mapping loads whole levels (16k tiles for the full scroll at 25 cm): it is expected
    # to stay blurred for the full run's stop; the quick run's small painting must sharpen.
    checks = {"all_sharp_after_stop": all(r["display_latency_frames"] is not None
                                          for r in res["rows"]
                                          if opts.quick or r["method"] != "lod-mapping")}
    if "hash" in by:
        # Deterministic quick run: each frame's loads arrive within the frame, so the hash
        # loop is sharp within a few frames of the stop (VT-mobile-VR: 3-4).
        if opts.quick:
            checks["hash_latency_at_most_5"] = (by["hash"]["display_latency_frames"] or 99) <= 5
        if "cpu-async" in by:
            checks["hash_not_slower_than_cpu_async"] = (
                (by["hash"]["display_latency_frames"] or 10 ** 9)
                <= (by["cpu-async"]["display_latency_frames"] or 10 ** 9))
    return rep.finish(checks, _report)


def _report(rep, res):
    rep.text(f"{'Quick' if res['quick'] else 'Full'} run, {res['frames']} frames.\n")
    rep.table(["method", "display latency (frames)", "(ms at 90 Hz)", "fps (paced)",
               "fps from frame time", "hit rate", "LOD memory MB"],
              [[r["method"], r["display_latency_frames"],
                None if r["display_latency_frames"] is None
                else 1e3 * r["display_latency_frames"] / 90, r["fps"], r["fps_from_frame_time"],
                f"{100 * r['hit_rate']:.1f}%", r.get("lod_memory_mb")] for r in res["rows"]])
    rep.text("VT-mobile-VR §5.5.2: ours 3-4 frames (33-44 ms), Unreal SVT ~30 frames (~500 ms).\n")
    rep.hit_rate_figure(res["rows"], [r["method"] for r in res["rows"]], "latency_hit_rate.png",
                        "hit rate per frame; the camera stops near the end")
    rep.checks(res["checks"])

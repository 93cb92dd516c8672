"""`single`: VT-mobile-VR §5.3. The main view 40 cm from the scroll with the magnifier, both moving
left to right at 1 m/s for 10 s, then a stop; threshold 16. Table 2 (processing methods: fps,
processing latency, hit rate), Table 3 (direct vs mip-by-mip: fps, fps std, display latency),
frames with and without the magnifier's requests, and the hash's losses under the frame salt."""

from __future__ import annotations

import numpy as np

from .. import views as v
from . import common as c

METHODS = ("cpu-async", "flag-array", "hash", "basic")


def setup(opts: c.Options):
    ex, pack = c.scroll_room(opts)
    if opts.quick:
        path = v.scroll_path(distance=0.40, speed=1.0, duration=0.12, start_x=0.3,
                             exhibition=ex, stop_frames=6)
    else:
        path = v.scroll_path(distance=0.40, speed=1.0, duration=opts.duration or 10.0,
                             start_x=1.0, exhibition=ex, stop_frames=60)
    return ex, pack, c.user_path(opts, path, ex)


def salt_losses(ex, path, frames: int, threads: int = 0) -> dict:
    """Requests the hash loses against the exact (basic) set, and how many of them it had
    also lost the frame before (VT-mobile-VR: the frame salt keeps that at zero)."""
    resident = ex.resident_set()
    basic, hashp = v.make_processor("basic", ex.tiles), v.make_processor("hash", ex.tiles, threads)
    lost_total = repeats = 0
    prev = np.zeros(0, np.uint64)
    n = min(frames, len(path))
    for f in range(n):
        bufs = v.feedback_buffers(ex, path, f, threads=threads)
        exact = basic.process(bufs, resident, f)["requests"]
        got = hashp.process(bufs, resident, f)["requests"]
        lost = np.setdiff1d(exact, got)
        lost_total += lost.size
        repeats += np.intersect1d(lost, prev).size
        prev = lost
    return {"frames": n, "lost": int(lost_total), "lost_twice_in_a_row": int(repeats)}


def run(opts: c.Options) -> dict:
    from tqdm import tqdm
    methods = c.check_methods(opts, METHODS, METHODS[:3])
    ex, pack, path = setup(opts)
    rep = c.Report("single", opts.out, "Scenario single: one scroll, eyes and magnifier "
                   "(VT-mobile-VR §5.3)")
    res = rep.results
    res["quick"] = opts.quick
    res["frames"] = len(path)
    res["painting"] = [ex.specs[0].width, ex.specs[0].height]
    res["table2"] = []
    runs = {}
    for m in tqdm(methods, desc="single: Table 2", unit="method"):
        loop = c.frame_loop(opts, ex, pack, path, method=m, strategy="direct")
        runs[m] = loop
        res["table2"].append(c.loop_row(loop, loop.run(), method=m, strategy="direct"))
    res["table3"] = []
    for strat in ("direct", "mip-by-mip"):
        if strat == "direct" and "hash" in runs:
            row = next(r for r in res["table2"] if r["method"] == "hash")
            res["table3"].append(row)
            continue
        loop = c.frame_loop(opts, ex, pack, path, method="hash", strategy=strat)
        res["table3"].append(c.loop_row(loop, loop.run(), method="hash", strategy=strat))

    # The magnifier with and without its own requests.
    shown = {}
    for with_req in (True, False):
        loop = c.frame_loop(opts, ex, pack, path, method="hash", strategy="direct",
                            magnifier_requests=with_req)
        loop.run()
        shown[with_req] = (loop.last_images, loop.records[-1]["view_hit_rates"])
    res["magnifier"] = {"hit_rate_with_requests": shown[True][1][-1],
                        "hit_rate_without_requests": shown[False][1][-1],
                        "eye_hit_rate_with": shown[True][1][0],
                        "eye_hit_rate_without": shown[False][1][0]}
    res["salt"] = salt_losses(ex, path, frames=len(path) if opts.quick else 200,
                              threads=opts.threads)

    # Invariants (tests assert them on the quick run).
    checks = {"methods_agree": c.methods_agree(ex, path, threads=opts.threads)}
    sync = [r for r in res["table2"] if r["method"] in ("basic", "flag-array", "hash")]
    checks["sync_latency_zero"] = all(r["latency_frames"] == 0 for r in sync)
    checks.update(c.loading_checks(res["table2"] + res["table3"][1:], opts.threshold,
                                   opts.quick))
    checks["magnifier_sharp_only_with_its_requests"] = (
        res["magnifier"]["hit_rate_with_requests"] == 1.0 and
        res["magnifier"]["hit_rate_without_requests"] < 1.0)
    checks["salt_no_loss_twice_in_a_row"] = res["salt"]["lost_twice_in_a_row"] == 0
    d, mm = (r["display_latency_frames"] for r in res["table3"])
    checks["direct_not_slower_than_mip_by_mip"] = d is not None and (mm is None or d <= mm)
    return rep.finish(checks, _report, shown)


def _report(rep, res, shown):
    rep.text(f"{'Quick (scaled-down) run' if res['quick'] else 'Full run'}: painting "
             f"{res['painting'][0]} x {res['painting'][1]}, {res['frames']} frames.\n")
    rep.text("## Table 2: request processing (direct loading, threshold as given)\n")
    rep.table(["method", "fps", "processing latency (frames, mean / max)", "hit rate",
               "display latency after stop (frames)"],
              [[r["method"], r["fps"],
                f"{r['latency_frames']:.2f} / {max(x['latency_frames'] for x in r['records'])}",
                f"{100 * r['hit_rate']:.2f}%", r["display_latency_frames"]]
               for r in res["table2"]])
    rep.text("VT-mobile-VR Table 2: CPU async 89.97 fps, 13.24 frames, 76.96%; flag array 89.73, "
             "2.00, 86.65%; hash 89.34, 2.00, 86.40%.\n")
    rep.text("## Table 3: loading strategies (hash)\n")
    rep.table(["strategy", "fps", "frame time std (ms)", "hit rate", "display latency (frames)"],
              [[r["strategy"], r["fps"], r["frame_ms_std"], f"{100 * r['hit_rate']:.2f}%",
                r["display_latency_frames"]] for r in res["table3"]])
    rep.text("VT-mobile-VR Table 3: mip-by-mip 89.76 fps (std 0.65), 6 frames; direct 89.81 "
             "(0.72), 3 frames.\n")
    rep.text("## Per-stage times (ms, mean per frame)\n")
    rows = res["table2"] + res["table3"][1:]
    rep.stage_table("method / strategy", rows, [f"{r['method']} / {r['strategy']}" for r in rows])
    rep.hit_rate_figure(rows, [f"{r['method']}/{r['strategy']}" for r in rows],
                        "single_hit_rate.png", "hit rate per frame")
    rep.text("## The magnifier with and without its requests (last frame)\n")
    m = res["magnifier"]
    rep.text(f"Magnifier hit rate with its requests {m['hit_rate_with_requests']:.3f}, "
             f"without {m['hit_rate_without_requests']:.3f} (eyes: {m['eye_hit_rate_with']:.3f} "
             f"/ {m['eye_hit_rate_without']:.3f}).\n")
    for with_req, label in ((True, "with"), (False, "without")):
        imgs = shown[with_req][0]
        rep.image(imgs[0], f"single_eye_{label}.png", f"left eye, {label} magnifier requests")
        if len(imgs) > 2:
            rep.image(imgs[2], f"single_magnifier_{label}.png",
                      f"magnifier, {label} its requests")
    s = res["salt"]
    rep.text(f"## Hash losses\n\nOver {s['frames']} frames the hash lost {s['lost']} requests "
             f"against the exact set; lost two frames in a row: {s['lost_twice_in_a_row']}.\n")
    rep.checks(res["checks"])

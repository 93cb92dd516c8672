"""`gigascroll bench views`: request-processing cost of the four methods against the number
of paintings (VT-mobile-VR Fig. 11, 8..40 paintings on tables) and against the tile total (five
steps of 4096 tiles, static camera 25 cm away, Fig. 12); the cpu-async latency in frames at
a 90 Hz pace; hash losses per frame and repeated losses against the table size and the salt.

Times are medians over frames of the same run; ratios compare methods within the run.
"""

from __future__ import annotations

import math
import statistics
import tempfile
import time
from pathlib import Path

from tqdm import tqdm

from .. import views as v
from ..experiments import (painting_sweep, pattern_image, pyplot, save_figure, spec_of,
                           time_processing, width_for_tiles, write_json)
from .._core import hardware_threads
from ..errors import UserError
from ..walk.frame_loop import STAGES, FrameLoop
from ..pack import build_pack

PAINTING_COUNTS = (8, 16, 24, 32, 40)
PARTS = ("paintings", "tiles", "latency", "losses", "loop", "pace")


def add_arguments(parser) -> None:
    parser.add_argument("--out", default="bench-views", help="output directory (JSON, PNG)")
    parser.add_argument("--frames", type=int, default=90,
                        help="frames per configuration (default 90 = 1 s at 90 Hz)")
    parser.add_argument("--latency-frames", type=int, default=180,
                        help="frames of the paced cpu-async latency run")
    parser.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="round-robin repeats of each sweep (the least disturbed is kept)")
    parser.add_argument("--quick", action="store_true", help="a few frames of everything")
    parser.add_argument("--part", choices=PARTS, action="append",
                        help="run only these parts (repeatable; default: all)")


def _painting_sweep(args, frames) -> list[dict]:
    return painting_sweep(PAINTING_COUNTS, frames, args.repeats, args.threads)


# VT-mobile-VR Fig. 12's five steps of 4096 tiles, then larger totals where a flag array shows.
TILE_TOTALS = tuple(4096 * k for k in range(1, 6)) + (1 << 18, 1 << 20, 1 << 22)


def _painting_with_tiles(total: int) -> v.PaintingSpec:
    """The scroll cropped or extended in width (same texel size) to about `total` tiles."""
    width = width_for_tiles(total, 6083)
    return v.PaintingSpec(f"crop{total}", width, 6083, 12.0 * width / 152089, 0.5)


def _tile_sweep(args, frames) -> list[dict]:
    configs, widths = [], []
    for total in tqdm(TILE_TOTALS, desc="feedback, tile totals", unit="config"):
        spec = _painting_with_tiles(total)
        ex = v.single_scroll(spec)
        x = min(6.0, spec.width_m / 2)
        path = v.scroll_path(distance=0.25, speed=0.0, duration=0.1, start_x=x,
                             magnifier=False, exhibition=ex)
        bufs = v.feedback_buffers(ex, path, 0, magnifier=None, threads=args.threads)
        configs.append((ex, [bufs] * frames))  # static camera: the same buffers every frame
        widths.append(spec.width)
    res = time_processing(configs, args.threads, args.repeats)
    return [{"tiles": ex.tiles[0].total_tiles, "width": w, **r}
            for (ex, _), w, r in zip(configs, widths, res)]


def _async_latency(args, frames) -> dict:
    """cpu-async in a loop paced at 90 Hz: feedback, submit, poll; latency = poll frame -
    submit frame of each result. When the loop cannot hold 90 Hz (feedback of three views on
    a shared machine), the loop-frame count understates it, so we also convert the worker's
    own submit-to-finish time into 90 Hz frames: the result is usable at the first frame
    boundary after it finished, ceil(seconds * 90)."""
    ex = v.single_scroll()
    path = v.scroll_path(duration=frames / v.FPS)
    resident = ex.resident_set()
    proc = v.AsyncProcessor()
    latencies, seconds = [], []
    period = 1.0 / v.FPS
    start = time.perf_counter()
    for frame in tqdm(range(len(path)), desc="cpu-async at 90 Hz", unit="frame"):
        proc.submit(v.feedback_buffers(ex, path, frame, threads=args.threads), frame)
        for r in proc.poll(resident):
            latencies.append(frame - r["frame"])
            seconds.append(r["seconds"])
        # Pace: sleep to the next 90 Hz boundary.
        delay = start + (frame + 1) * period - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    tail = proc.poll(resident, wait=True)
    latencies += [len(path) - r["frame"] for r in tail]
    seconds += [r["seconds"] for r in tail]
    elapsed = time.perf_counter() - start
    at90 = [math.ceil(s * v.FPS) for s in seconds]
    return {"frames": len(path), "mean": statistics.mean(latencies),
            "max": max(latencies), "min": min(latencies),
            "achieved_fps": len(path) / elapsed,
            "worker_ms_median": 1e3 * statistics.median(seconds),
            "worker_ms_max": 1e3 * max(seconds),
            "frames_at_90hz_mean": statistics.mean(at90), "frames_at_90hz_max": max(at90)}


def _hash_losses(args, frames) -> list[dict]:
    ex = v.single_scroll()
    path = v.scroll_path(duration=frames / v.FPS)
    resident = ex.resident_set()
    basic = v.BasicProcessor()
    bits_list = (12, 14, 16, 18)
    salted = {b: v.HashProcessor(b, threads=args.threads) for b in bits_list}
    fixed = {b: v.HashProcessor(b, threads=args.threads) for b in bits_list}
    stats = {b: {"lost": 0, "repeat": 0, "fixed_lost": 0, "fixed_repeat": 0} for b in bits_list}
    prev = {b: set() for b in bits_list}
    prev_fixed = {b: set() for b in bits_list}
    requests = []
    for frame in tqdm(range(len(path)), desc="hash losses", unit="frame"):
        bufs = v.feedback_buffers(ex, path, frame, threads=args.threads)
        ref = set(basic.process(bufs, resident)["requests"].tolist())
        requests.append(len(ref))
        for b in bits_list:
            lost = ref - set(salted[b].process(bufs, resident, frame)["requests"].tolist())
            lf = ref - set(fixed[b].process(bufs, resident, 1)["requests"].tolist())
            s = stats[b]
            s["lost"] += len(lost)
            s["repeat"] += len(lost & prev[b])
            s["fixed_lost"] += len(lf)
            s["fixed_repeat"] += len(lf & prev_fixed[b])
            prev[b], prev_fixed[b] = lost, lf
    n = len(path)
    return [{"table_bits": b, "slots": 1 << b, "requests_per_frame": statistics.mean(requests),
             "lost_per_frame": s["lost"] / n, "repeated_losses": s["repeat"],
             "fixed_salt_lost_per_frame": s["fixed_lost"] / n,
             "fixed_salt_repeated_losses": s["fixed_repeat"], "frames": n}
            for b, s in stats.items()]


def _loop(args, quick) -> list[dict]:
    """The first frame loop (VT-mobile-VR Tables 2, 3 set-up, scaled down): a synthetic painting
    at the scroll's texel size, eyes at 40 cm plus the magnifier, 1 m/s then a stop, paced at
    90 Hz with the lock-free loader thread; Table 2's methods with direct loading, and
    mip-by-mip with the hash."""
    width, height = (12000, 1600) if quick else (24000, 1600)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        pack = build_pack([pattern_image(width, height)], Path(d) / "loop.pack")
        ex = v.single_scroll(spec_of("loop", width, height))
        moving = 0.2 if quick else 1.2
        path = v.scroll_path(distance=0.40, speed=1.0, duration=moving, start_x=0.3,
                             exhibition=ex, stop_frames=10 if quick else 60)
        for method, strategy in (("cpu-async", "direct"), ("flag-array", "direct"),
                                 ("hash", "direct"), ("hash", "mip-by-mip")):
            loop = FrameLoop(ex, pack, path, method=method, strategy=strategy,
                             pace=True, threads=args.threads)
            s = loop.run(progress=True)
            rows.append({"method": method, "strategy": strategy, **s})
    return rows


def _pace(args, quick) -> dict:
    """How fast the frame loop can go: the hash / direct loop not paced (flat out), eyes at
    1800 x 1920 (feedback 225 x 240) and the 512 x 512 magnifier, 40 cm from a synthetic
    painting as high as the scroll (6083 texels, 0.5 m: what the eyes see of it is what
    costs) and 24000 texels wide (the passes do not depend on the width), 1 s at 1 m/s then
    10 still frames. Wall time per frame includes the
    loop's own measurement (the exact request set for the hit rate)."""
    width, height = (6000, 1600) if quick else (24000, 6083)
    with tempfile.TemporaryDirectory() as d:
        pack = build_pack([pattern_image(width, height)], Path(d) / "pace.pack")
        ex = v.single_scroll(spec_of("pace", width, height))
        path = v.scroll_path(distance=0.40, speed=1.0, duration=0.1 if quick else 1.0,
                             start_x=0.3, exhibition=ex, stop_frames=10)
        loop = FrameLoop(ex, pack, path, method="hash", strategy="direct", pace=False,
                         threads=args.threads)
        s = loop.run(progress=True)
    r = loop.records
    wall = (r[-1]["time_s"] - r[0]["time_s"]) / (len(r) - 1)
    return {**s, "wall_ms": 1e3 * wall, "wall_fps": 1.0 / wall,
            "stage_ms_sum": statistics.mean(x["total_ms"] for x in r)}


def _plot(rows, key, xlabel, path, log_x=False):
    fig, axes = pyplot().subplots(1, 2, figsize=(11, 4))
    xs = [r[key] for r in rows]
    for ax, field, label in ((axes[0], "cpu_ms", "CPU time per frame, all threads (ms)"),
                             (axes[1], "ms", "wall time per frame (ms)")):
        for m in v.PROCESSING_METHODS:
            ax.plot(xs, [r[m][field] for r in rows], marker="o", label=m)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(label + ", median")
        ax.set_ylim(bottom=0)
        if log_x:
            ax.set_xscale("log")
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def _plot_pace(p: dict, path) -> None:
    """One stacked bar of the loop's mean stage times against the 90 Hz frame budget."""
    fig, ax = pyplot().subplots(figsize=(9, 2.6))
    left = 0.0
    for s in STAGES:
        w = p[s + "_ms"]
        ax.barh([0], [w], left=left, label=f"{s} {w:.2f}")
        left += w
    ax.barh([0], [p["wall_ms"] - left], left=left, color="0.8",
            label=f"outside the stages {p['wall_ms'] - left:.2f}")
    ax.axvline(1000 / v.FPS, color="k", linestyle="--", label="90 Hz budget 11.1")
    ax.set_yticks([])
    ax.set_xlabel("ms per frame (mean), flat out: hash / direct, eyes + 512 x 512 magnifier")
    ax.legend(ncol=4, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.35))
    save_figure(fig, path, dpi=120, bbox_inches="tight")


def _table(rows, key, label) -> str:
    """Markdown: CPU ms (wall ms) per method, and the flag-array / hash ratio of CPU time."""
    lines = [f"| {label} | tiles | requests/frame | basic | cpu-async | flag-array | hash | "
             f"flag/hash (CPU) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r[key]} | {r['tiles']} | {r['hash']['requests']:.0f} | " +
                     " | ".join(f"{r[m]['cpu_ms']:.3f} ({r[m]['ms']:.3f})"
                                for m in v.PROCESSING_METHODS) +
                     f" | {r['flag-array']['cpu_ms'] / r['hash']['cpu_ms']:.2f} |")
    first, last = rows[0], rows[-1]
    lines.append("")
    lines.append("CPU time growth first -> last: " + ", ".join(
        f"{m} x{last[m]['cpu_ms'] / first[m]['cpu_ms']:.2f}" for m in v.PROCESSING_METHODS))
    return "\n".join(lines)


def run(args) -> int:
    if args.frames < 1 or args.latency_frames < 1 or args.repeats < 1:
        raise UserError("--frames, --latency-frames and --repeats must be >= 1")
    if args.threads < 0:
        raise UserError("--threads must be >= 0")
    frames = 5 if args.quick else args.frames
    latency_frames = 20 if args.quick else args.latency_frames
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    if args.quick:
        args.repeats = 1
    results = {"frames": frames, "repeats": args.repeats,
               "machine_threads": hardware_threads()}
    parts = set(args.part or PARTS)
    if "paintings" in parts:
        results["paintings"] = _painting_sweep(args, frames)
        _plot(results["paintings"], "paintings", "paintings in the exhibition",
              out / "views_paintings.png")
        print("## Request processing vs painting count (CPU ms of all threads (wall ms) per "
              "frame, median)\n")
        print(_table(results["paintings"], "paintings", "paintings"))
    if "tiles" in parts:
        results["tile_totals"] = _tile_sweep(args, frames)
        _plot(results["tile_totals"], "tiles", "tiles in the pack (all levels)",
              out / "views_tiles.png", log_x=True)
        print("\n## Request processing vs tile total (static camera 25 cm; CPU ms (wall ms) "
              "per frame, median)\n")
        print(_table(results["tile_totals"], "tiles", "tile total"))
    if "latency" in parts:
        a = results["async_latency"] = _async_latency(args, latency_frames)
        print(f"\n## cpu-async latency, loop paced at 90 Hz (achieved {a['achieved_fps']:.1f} "
              f"frames/s) over {a['frames']} frames: mean {a['mean']:.2f}, min {a['min']}, "
              f"max {a['max']} frames; worker submit-to-finish median {a['worker_ms_median']:.2f} "
              f"ms (max {a['worker_ms_max']:.2f}) = {a['frames_at_90hz_mean']:.2f} frames at 90 Hz "
              f"(max {a['frames_at_90hz_max']})\n")
    if "losses" in parts:
        results["hash_losses"] = _hash_losses(args, max(frames, 20) if args.quick else 900)
        print("## Hash losses on the 10 s scroll path (eyes + magnifier)\n")
        print("| slots | requests/frame | lost/frame | lost 2 frames in a row | "
              "fixed salt: lost/frame | fixed salt: in a row |")
        print("|---|---|---|---|---|---|")
        for h in results["hash_losses"]:
            print(f"| 2^{h['table_bits']} | {h['requests_per_frame']:.0f} | "
                  f"{h['lost_per_frame']:.3f} | {h['repeated_losses']} | "
                  f"{h['fixed_salt_lost_per_frame']:.3f} | {h['fixed_salt_repeated_losses']} |")
    if "loop" in parts:
        results["loop"] = _loop(args, args.quick)
        print("\n## Frame loop paced at 90 Hz (eyes + magnifier, 1 m/s then stop)\n")
        print("| method | loading | fps | fps std (ms) | hit rate | processing latency | "
              "display latency | feedback | processing | issue | drain | update | display |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in results["loop"]:
            print(f"| {r['method']} | {r['strategy']} | {r['fps']:.1f} | {r['frame_ms_std']:.2f} | "
                  f"{100 * r['hit_rate']:.1f}% | {r['latency_frames']:.2f} | "
                  f"{r['display_latency_frames']} | " +
                  " | ".join(f"{r[s + '_ms']:.2f}" for s in STAGES) + " |")
    if "pace" in parts:
        p = results["pace"] = _pace(args, args.quick)
        _plot_pace(p, out / "views_pace.png")
        print(f"\n## Frame loop flat out (hash / direct, eyes + 512 x 512 magnifier, "
              f"{p['frames']} frames)\n")
        print("| feedback | processing | issue | drain | update | display | stages | wall | fps |")
        print("|---|---|---|---|---|---|---|---|---|")
        print(" | ".join([""] + [f"{p[s + '_ms']:.2f}" for s in STAGES] +
                         [f"{p['stage_ms_sum']:.2f}", f"{p['wall_ms']:.2f}",
                          f"{p['wall_fps']:.1f}", ""]).strip())
    name = "views.json" if parts == set(PARTS) else f"views_{'_'.join(sorted(parts))}.json"
    write_json(out / name, results, indent=1)
    print(f"\nwrote {out / name} and the plots of the sweeps run")
    return 0

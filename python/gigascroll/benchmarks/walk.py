"""`gigascroll bench walk`: the gallery walk's goals (issue 14 §5), measured in one run.

- display cost per pixel against a bare Embree primary-ray cast of the same pixels (same
  cameras, alternated, median of --repeats; both timed around their Python call, the display
  rendering into an image kept between frames): per eye (the left eye alone) and in stereo
  (both eyes with the right eye's reuse, against the bare cast of both eyes' pixels);
- the right eye with reuse against the left eye, over poses of the scroll walk;
- the whole loop's frame rate at 1800 x 1920 per eye, and at smaller sizes down to the largest
  per-eye resolution whose mean frame time fits 90 Hz;
- display latency after each stop and the streamed frames' error against their oracle.
"""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

import numpy as np

from ..outputs import write_text


def add_arguments(p) -> None:
    p.add_argument("--pack", default=None,
                   help="tile pack (default: build/demo/painting.pack, else the built-in painting)")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--frames", type=int, default=12, help="loop frames per resolution")
    p.add_argument("--photons", type=int, default=1 << 17)
    p.add_argument("--out", default="bench/walk/results.json")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--parts", default="display,stereo,reuse,loop,stops",
                   help="comma-separated subset of display (per eye), stereo, reuse, loop, stops")
    p.add_argument("--eye", default="450x480,900x960,1800x1920",
                   help="comma-separated per-eye sizes WxH of the display and stereo parts")


def _num(x) -> str:
    """A ratio to two places, or '-' where there is none (a timer that read zero)."""
    return "-" if x is None else f"{x:.2f}"


class _Alternation:
    """A display and the bare cast of the same pixels, alternated and each timed the same way:
    around the Python call, wall (per call) and process CPU time (summed, both threads)."""

    def __init__(self):
        self.display, self.bare, self.display_cpu, self.bare_cpu = [], [], 0.0, 0.0

    def run(self, display, cast, repeats):
        for _ in range(repeats):
            t, c = time.perf_counter(), time.process_time()
            display()
            self.display.append(time.perf_counter() - t)
            self.display_cpu += time.process_time() - c
            t, c = time.perf_counter(), time.process_time()
            cast()
            self.bare.append(time.perf_counter() - t)
            self.bare_cpu += time.process_time() - c

    def row(self, eye, pixels):
        """Per pixel, the median display and bare cast and their ratio; the same ratio in CPU
        time (less exposed than wall time to the other jobs of a shared machine), and of the
        fastest display to the fastest cast (the other jobs only ever add time)."""
        row = {"eye": eye, "display_ns_per_pixel": 1e9 * statistics.median(self.display) / pixels,
               "bare_rays_ns_per_pixel": 1e9 * statistics.median(self.bare) / pixels}
        row["ratio"] = row["display_ns_per_pixel"] / row["bare_rays_ns_per_pixel"]
        row["cpu_ratio"] = self.display_cpu / self.bare_cpu if self.bare_cpu > 0 else None
        row["min_ratio"] = min(self.display) / min(self.bare) if min(self.bare) > 0 else None
        return row


def _pack(arg):
    from ..commands.gallery import builtin_pack
    from ..pack import TilePack
    if arg:
        return TilePack(Path(arg))
    demo = Path("build/demo/painting.pack")
    return TilePack(demo) if (demo / "manifest.json").is_file() else builtin_pack()


def lit_scroll_walk(args):
    """(pack, room, source, path): the --pack (or demo) painting in the built-in scroll room,
    lit and baked with --photons, and its 4 s default walk; the walk benchmarks' common scene."""
    from ..gallery import builtin_room
    from ..walk.gallery_walk import GallerySource, walk_path
    pack = _pack(args.pack)
    room = builtin_room("scroll", pack)
    t0 = time.perf_counter()
    src = GallerySource(room, pack, "baked", photons=args.photons, threads=args.threads)
    print(f"scroll room lit and baked in {time.perf_counter() - t0:.1f} s")
    return pack, room, src, walk_path(room, seconds=4.0)


def run(args) -> int:
    from .. import runtime
    from .. import views as v
    from .._core import DisplayPass
    from ..walk.gallery_walk import parent_keys
    from ..views.exhibition import Headset

    parts = {x.strip() for x in args.parts.split(",") if x.strip()}
    unknown = parts - {"display", "stereo", "reuse", "loop", "stops"}
    if unknown:
        raise ValueError(f"--parts: unknown part(s) {', '.join(sorted(unknown))}")
    from ..commands.gallery import parse_eye
    display_sizes = [parse_eye(x) for x in args.eye.split(",") if x.strip()]
    if not display_sizes:
        raise ValueError("--eye: give at least one per-eye size WxH")
    pack, room, src, path = lit_scroll_walk(args)
    thr = args.threads
    results = {"pack": str(pack.path), "machine": "2 cores, shared", "date": time.strftime("%Y-%m-%d")}

    # A VT holding every tile the measured frames ask for (the cost of the display, not of
    # missing tiles): before each pose is timed, its feedback's requests and their parents
    # (trilinear's second level) are made resident, as the walk's oracle does. Without it
    # the display sampled the pinned coarse tail only (every lookup a fallback).
    vt = runtime.VirtualTexture(pack, (64, 64))
    levels = np.array([t.levels for t in src.tiles], np.int64)
    poses = list(range(0, len(path), max(1, len(path) // 6)))

    def eyes(frame, w, h):
        views = v.frame_cameras(path, frame, headset=Headset(width=w, height=h), magnifier=None)
        needed = np.concatenate([src.feedback(cam, fw, fh, thr).ravel()
                                 for cam, fw, fh in views[:2]])
        needed = np.unique(needed[needed != v.NO_REQUEST])
        needed = np.concatenate([needed, parent_keys(needed, levels)])
        missing = vt.request(needed)
        for key in zip(*(a.tolist() for a in v.unpack_requests(missing))):
            vt.insert(key, pack.read_tile(*key))
        warm_tiles.append(int(needed.size))
        return views[0][0], views[1][0]
    warm_tiles = []

    # 1. display vs bare primary rays, per pixel, at each --eye size (default up to the headset's).
    rows = []
    for w, h in display_sizes if "display" in parts else ():
        d = DisplayPass()
        out = np.empty((h, w, 3), np.float32)  # kept between frames, as the walk keeps it
        timing = _Alternation()
        for frame in poses[:3]:
            left, _ = eyes(frame, w, h)
            src.display(d, vt, left, thr, out=out)  # warm
            timing.run(lambda: src.display(d, vt, left, thr, out=out),
                       lambda: src.primary_rays(left, thr), args.repeats)
        row = timing.row(f"{w}x{h}", w * h)
        split = d.left_stats
        row["split_ms"] = {k: 1e3 * split[f"{k}_seconds"] for k in ("rays", "vt", "shade")}
        rows.append(row)
        print(f"display {w}x{h}: {row['display_ns_per_pixel']:.1f} ns/px, bare rays "
              f"{row['bare_rays_ns_per_pixel']:.1f} ns/px, ratio {row['ratio']:.2f} "
              f"(CPU time {_num(row['cpu_ratio'])}, minima {_num(row['min_ratio'])}; rays/vt/shade ms "
              f"{row['split_ms']})")
    results["display_vs_rays"] = rows

    # 1b. the same for both eyes: the stereo display with reuse (what the walk runs: the left
    # eye, the reuse projection and the right eye's remaining pixels) per pixel of both eyes,
    # against the bare cast of both eyes' pixels (left and right camera), alternated.
    stereo_rows = []
    for w, h in display_sizes if "stereo" in parts else ():
        d = DisplayPass()
        outs = (np.empty((h, w, 3), np.float32), np.empty((h, w, 3), np.float32))
        timing = _Alternation()
        for frame in poses[:3]:
            left, right = eyes(frame, w, h)
            src.display_stereo(d, vt, left, right, True, thr, *outs)  # warm
            timing.run(lambda: src.display_stereo(d, vt, left, right, True, thr, *outs),
                       lambda: (src.primary_rays(left, thr), src.primary_rays(right, thr)), args.repeats)
        row = timing.row(f"{w}x{h}", 2 * w * h)
        row["reused_share"] = d.right_stats["reused"] / d.right_stats["pixels"]
        stereo_rows.append(row)
        print(f"stereo display {w}x{h} per eye (both eyes with reuse): "
              f"{row['display_ns_per_pixel']:.1f} ns/px, bare rays (both eyes) "
              f"{row['bare_rays_ns_per_pixel']:.1f} ns/px, ratio {row['ratio']:.2f} "
              f"(CPU time {_num(row['cpu_ratio'])}, minima {_num(row['min_ratio'])}; "
              f"{100 * row['reused_share']:.0f} % of the right eye reused)")
    results["stereo_display_vs_rays"] = stereo_rows
    results["resident_tiles_per_pose"] = max(warm_tiles, default=0)
    print(f"tiles made resident per pose (at most): {results['resident_tiles_per_pose']} "
          f"of {64 * 64} slots")
    # The two readings of the goal side by side (wall / CPU-time / minima ratio to the bare cast).
    print("display / bare rays per pixel, wall / CPU / minima:  per eye (left alone)  stereo (both eyes, reuse)")

    def pair(row):
        return f"{row['ratio']:.2f} / {_num(row['cpu_ratio'])} / {_num(row['min_ratio'])}" if row else "-"
    per_eye = {r["eye"]: r for r in rows}
    stereo = {r["eye"]: r for r in stereo_rows}
    for eye in dict.fromkeys([*per_eye, *stereo]):
        print(f"  {eye:>10}  {pair(per_eye.get(eye)):>30}  {pair(stereo.get(eye)):>25}")

    if "reuse" in parts:
        _right_vs_left(src, vt, poses, eyes, thr, args, results)
    if "loop" in parts:
        _loop(src, pack, path, thr, args, results)
    if "stops" in parts:
        _stops(src, pack, room, thr, results)

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, json.dumps(results, indent=1))
    print(f"wrote {out}")
    return 0


def _right_vs_left(src, vt, poses, eyes, thr, args, results) -> None:
    """2. the right eye with reuse against the left eye, along the walk."""
    from .._core import DisplayPass
    w, h = 900, 960
    d = DisplayPass()
    outs = (np.empty((h, w, 3), np.float32), np.empty((h, w, 3), np.float32))
    ratios, shares, lefts, rights, no_reuse = [], [], [], [], []
    for frame in poses:
        left, right = eyes(frame, w, h)
        src.display_stereo(d, vt, left, right, True, thr, *outs)
        for _ in range(max(1, args.repeats // 2)):
            src.display_stereo(d, vt, left, right, True, thr, *outs)
            ls, rs = d.left_stats, d.right_stats
            lefts.append(ls["total_seconds"])
            rights.append(rs["total_seconds"])
            shares.append(rs["reused"] / rs["pixels"])
            src.display_stereo(d, vt, left, right, False, thr, *outs)
            no_reuse.append(d.right_stats["total_seconds"])
    results["right_vs_left"] = {
        "eye": f"{w}x{h}", "left_ms": 1e3 * statistics.median(lefts),
        "right_ms": 1e3 * statistics.median(rights),
        "right_without_reuse_ms": 1e3 * statistics.median(no_reuse),
        "ratio": statistics.median(rights) / statistics.median(lefts),
        "reused_share": statistics.mean(shares)}
    print(f"right eye with reuse / left eye: {results['right_vs_left']['ratio']:.2f} "
          f"({100 * results['right_vs_left']['reused_share']:.0f} % reused)")


def _loop(src, pack, path, thr, args, results) -> None:
    """3. the whole loop's frame rate per eye size, with the magnifier and without (oracle off)."""
    from .. import views as v
    from ..walk.gallery_walk import GalleryWalk
    sizes = [(1800, 1920), (900, 960), (450, 480), (225, 240), (112, 120), (56, 60)]
    short = v.CameraPath(path.position[:args.frames], path.forward[:args.frames],
                         path.up[:args.frames], path.magnifier_target[:args.frames],
                         path.magnifier_normal[:args.frames], path.fps)
    for magnifier in (True, False):
        fps_rows = []
        for w, h in sizes:
            walk = GalleryWalk(src, pack, short, eye=(w, h), oracle=False, threads=thr,
                               magnifier=magnifier)
            walk.run()
            rec = walk.records[1:] or walk.records  # the first frame pays for warming up
            mean_ms = statistics.mean(r["total_ms"] for r in rec)
            fps_rows.append({"eye": f"{w}x{h}", "frame_ms": mean_ms, "fps": 1e3 / mean_ms,
                             "display_ms": statistics.mean(r["display_ms"] for r in rec),
                             "feedback_ms": statistics.mean(r["feedback_ms"] for r in rec)})
            print(f"loop {w}x{h}{'' if magnifier else ' (no magnifier)'}: {mean_ms:.1f} ms/frame "
                  f"= {1e3 / mean_ms:.1f} fps (display {fps_rows[-1]['display_ms']:.1f} ms, "
                  f"feedback {fps_rows[-1]['feedback_ms']:.1f} ms)")
        holding = [r for r in fps_rows if r["frame_ms"] <= 1e3 / 90]
        suffix = "" if magnifier else "_no_magnifier"
        results["loop_fps" + suffix] = fps_rows
        results["largest_eye_at_90hz" + suffix] = holding[0]["eye"] if holding else None


def _stops(src, pack, room, thr, results) -> None:
    """4. display latency after stops and convergence to the oracle (the loads of each frame
    drained when they arrive: a real loop, not waiting)."""
    from ..walk.gallery_walk import GalleryWalk, walk_path
    walk = GalleryWalk(src, pack, walk_path(room, seconds=2.0), eye=(225, 240), threads=thr)
    s = walk.run()
    results["stops"] = s["stops"]
    results["error_final"] = s["error_final"]
    print(f"stops: {s['stops']}; last frame's error vs oracle {s['error_final']}")

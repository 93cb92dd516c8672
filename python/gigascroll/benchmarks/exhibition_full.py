"""`gigascroll bench exhibition-full`: the virtual texturing paper's §5.4 hall (Fig. 11,
Table 5) at the scans' full resolution, where the `multi` scenario and the `hall` room run
them at 1/16 per axis.

- build: eight synthetic scans of exactly the Table 4 sizes (the built-in ink landscape,
  seeds 0..7, tiled BigTIFFs, about 6 Gpixel together), packed with `--workers` Dask workers
  into one pack of 40 paintings: the eight scans and 32 instances (five copies of each, as the
  paper's hall; painting i shows scan i % 8), so the tile data is stored once. Recorded: the
  synth and build times, the peak resident memory of this process and its children (Dask's
  workers) sampled every 0.2 s, the disk of the scans and of the pack, and what 40 stored
  copies would take;
- multi: the 40 paintings on five tables, the camera 170 cm high walking along them
  (`views.multi_route`), both eyes and the magnifier, direct loading (16 tiles a frame),
  45 x 45 slots, paced at 90 Hz, for each method: fps, per-stage ms (Table 5), hit rate,
  requests, tiles issued and loaded per frame;
- hall: the `hall` room with the 40 paintings (unlit: the views' scene, as `view --unlit`),
  walked along its first painting at 40 cm with a close look at 28 cm (the gallery walk's
  default path; from there the full-size scans are sampled at level 0-1), the same figures.

`--scale 1/N` (N a power of two) runs the same at 1/N per axis with the physical sizes kept
(1/16: the figures beside bench/RESULTS.md's `multi`; 1/256: a smoke run). Scans and pack go
to `--work` and are reused when present and complete (`--rebuild` replaces them)."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import threading
import time
from fractions import Fraction
from pathlib import Path

from ..outputs import write_text

STAGES = ("feedback", "processing", "issue", "drain", "update", "display")
COPIES = 5


def add_arguments(p) -> None:
    p.add_argument("--scale", required=True,
                   help="required, as the run's cost depends on it: 1 (full size, about 6 "
                   "Gpixel of scans, ~40 GB of disk, tens of minutes) or 1/N, N a power of "
                   "two: the scans at 1/N per axis, physical sizes kept (1/16: the multi "
                   "scenario's; 1/256: a smoke run)")
    p.add_argument("--work", default="bench/exhibition-full/work",
                   help="scans and pack (full size: ~18 GB of scans, the pack about as much "
                   "with zstd; reused when complete)")
    p.add_argument("--out", default="bench/exhibition-full/results.json")
    p.add_argument("--workers", type=int, default=2, help="Dask workers of the pack build")
    p.add_argument("--codec", default="zstd", choices=["raw", "zstd"])
    p.add_argument("--parts", default="build,multi,hall",
                   help="comma-separated subset of build, multi, hall")
    p.add_argument("--methods", default="flag-array,hash",
                   help="request-processing methods of the multi part")
    p.add_argument("--seconds", type=float, default=3.0,
                   help="camera motion of the multi route and of the hall walk, seconds")
    p.add_argument("--eye", default="1800x1920", help="per-eye size WxH of the hall walk")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--no-pace", action="store_true",
                   help="run the frame loops flat out instead of at 90 Hz")
    p.add_argument("--rebuild", action="store_true", help="rebuild scans and pack")


def parse_scale(text: str) -> Fraction:
    """1 or 1/N with N a power of two (ValueError otherwise)."""
    try:
        s = Fraction(str(text).strip())
    except (ValueError, ZeroDivisionError):
        raise ValueError(f"--scale must be 1 or 1/N (N a power of two), got {text!r}") from None
    n = s.denominator
    if s.numerator != 1 or n & (n - 1) or n > 4096:
        raise ValueError(f"--scale must be 1 or 1/N with N a power of two up to 4096, got {text!r}")
    return s


def parse_eye(text: str) -> tuple[int, int]:
    """WxH, each in [16, 16384] (ValueError otherwise)."""
    w, x, h = str(text).lower().partition("x")
    if not (x and w.isascii() and w.isdigit() and h.isascii() and h.isdigit()
            and 16 <= int(w) <= 16384 and 16 <= int(h) <= 16384):
        raise ValueError(f"--eye must be WxH with sides in [16, 16384], got {text!r}")
    return int(w), int(h)


def scaled_specs(scale: Fraction):
    """The eight Table 4 paintings at `scale` per axis (sizes rounded up), physical sizes
    kept."""
    from .. import views as v
    n = scale.denominator
    return [v.PaintingSpec(s.name if n == 1 else f"{s.name}_1_{n}", -(-s.width // n),
                           -(-s.height // n), s.width_m, s.height_m)
            for s in v.TABLE4_PAINTINGS]


class PeakMemory:
    """Peak resident memory of this process plus its descendants (Dask's nanny and worker
    processes), sampled every `period` seconds on a thread while in the `with` block."""

    def __init__(self, period: float = 0.2):
        self.period, self.peak, self._stop = period, 0, threading.Event()

    def _sample(self) -> int:
        import psutil
        me = psutil.Process()
        total = 0
        for p in [me, *me.children(recursive=True)]:
            try:
                total += p.memory_info().rss
            except psutil.Error:
                pass
        return total

    def _run(self) -> None:
        while not self._stop.wait(self.period):
            self.peak = max(self.peak, self._sample())

    def __enter__(self):
        self.peak = self._sample()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, self._sample())


def _bytes(path: Path) -> int:
    if path.is_file():
        return path.stat().st_size
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def synth_scans(work: Path, specs, rebuild: bool) -> tuple[list[Path], float]:
    """The eight scans (seed i for scan i), each written once: a scan is reused when its
    stamp says it is complete at this size and seed. Returns (paths, seconds spent)."""
    from ..pack.synth import synth_painting
    work.mkdir(parents=True, exist_ok=True)
    paths, spent = [], 0.0
    for i, s in enumerate(specs):
        path, stamp = work / f"scan{i}.tif", work / f"scan{i}.json"
        want = {"width": s.width, "height": s.height, "seed": i}
        if (not rebuild and path.is_file() and stamp.is_file()
                and json.loads(stamp.read_text()) == want):
            paths.append(path)
            continue
        stamp.unlink(missing_ok=True)
        t0 = time.perf_counter()
        synth_painting(path, s.width, s.height, seed=i)
        spent += time.perf_counter() - t0
        write_text(stamp, json.dumps(want) + "\n")
        paths.append(path)
    return paths, spent


def build(args, work: Path, specs) -> tuple[dict, Path]:
    """Scans and the 40-painting pack of instances; the build's figures."""
    from .. import TilePack
    from ..pack import build_pack
    try:
        import distributed  # noqa: F401  (and its psutil, for the peak memory)
    except ImportError:
        raise ValueError("the build part runs on Dask: install the cluster extra "
                         "(pip install 'gigascroll[cluster]')") from None
    scans, synth_s = synth_scans(work / "scans", specs, args.rebuild)
    pack_path = work / "hall40.pack"
    names = [s.name for s in specs]
    instances = [(f"{s.name}_copy{c}", i) for c in range(1, COPIES) for i, s in enumerate(specs)]
    res = {"synth_s": synth_s, "scans_bytes": sum(_bytes(p) for p in scans),
           "scan_pixels": sum(s.width * s.height for s in specs)}
    if not args.rebuild and (pack_path / "manifest.json").is_file():
        pack = TilePack(pack_path)
        if [p.name for p in pack.paintings] == names + [n for n, _ in instances]:
            res.update(reused_pack=True)
            return _pack_figures(res, pack, pack_path), pack_path
    with PeakMemory() as mem:
        t0 = time.perf_counter()
        pack = build_pack(scans, pack_path, codec=args.codec, names=names, instances=instances,
                          workers=args.workers, force=True, timeout=600)
        res["build_s"] = time.perf_counter() - t0
    res.update(reused_pack=False, build_peak_rss_mb=mem.peak / 2**20,
               build_mpixel_per_s=res["scan_pixels"] / 1e6 / res["build_s"])
    return _pack_figures(res, pack, pack_path), pack_path


def _pack_figures(res: dict, pack, path: Path) -> dict:
    stored = sum(_bytes(path / f) for f in pack.tile_files)
    res.update(pack_bytes=_bytes(path), pack_tiles_bytes=stored, paintings=len(pack.paintings),
               stored_paintings=sum(p.instance_of is None for p in pack.paintings),
               tile_count=pack.tile_count, codec=pack.codec,
               copies_estimate_bytes=COPIES * stored + (_bytes(path) - stored))
    return res


def _loop_figures(summary: dict, records: list) -> dict:
    n = max(1, len(records))
    return {**summary, "issued_per_frame": sum(r["issued"] for r in records) / n,
            "loaded_per_frame": sum(r["loaded"] for r in records) / n}


def multi(args, pack, specs) -> list[dict]:
    """Fig. 11 / Table 5 at this scale: the 40-painting route, per method."""
    from .. import views as v
    from ..walk.frame_loop import FrameLoop
    n = COPIES * len(specs)
    ex = v.multi_exhibition(n, specs)
    path = v.multi_route(n, duration=args.seconds, specs=specs)
    rows = []
    for m in [x for x in args.methods.split(",") if x]:
        loop = FrameLoop(ex, pack, path, method=m, strategy="direct", per_frame=16,
                         slots=(45, 45), pace=not args.no_pace, threads=args.threads)
        summary = loop.run()
        rows.append({"method": m, "tiles": sum(t.total_tiles for t in ex.tiles),
                     **_loop_figures(summary, loop.records)})
    return rows


def hall(args, pack, specs, scale: Fraction) -> dict:
    """The hall room with the 40 paintings (slot k shows pack painting k: the scans and their
    instances), walked along its first painting (the gallery walk's default path)."""
    from ..room.builtin import TEXEL_M, hall_room
    from ..walk.gallery_walk import ExhibitionSource, GalleryWalk, walk_path
    n = COPIES * len(specs)
    room = hall_room(specs, n, texel_m=TEXEL_M * scale.denominator)
    room = dataclasses.replace(room, paintings=[dataclasses.replace(s, painting=k)
                                                for k, s in enumerate(room.paintings)])
    w, h = parse_eye(args.eye)
    walk = GalleryWalk(ExhibitionSource(room, pack), pack, walk_path(room, args.seconds),
                       eye=(w, h), oracle=False, pace=not args.no_pace, threads=args.threads)
    summary = walk.run()
    keep = ("frames", "eye", "fps", "fps_from_frame_time", "frame_ms_std", "hit_rate",
            "requests_per_frame", *[f"{s}_ms" for s in ("feedback", "processing", "issue",
                                                        "drain", "update", "display", "total")])
    return _loop_figures({k: summary[k] for k in keep if k in summary}, walk.records)


def run(args) -> int:
    from .. import TilePack
    scale = parse_scale(args.scale)
    parts = {p for p in args.parts.split(",") if p}
    if not parts <= {"build", "multi", "hall"} or not parts:
        raise ValueError(f"--parts: a comma-separated subset of build, multi, hall, got "
                         f"{args.parts!r}")
    if not (math.isfinite(args.seconds) and 0 < args.seconds <= 600):
        raise ValueError(f"--seconds must be in (0, 600], got {args.seconds}")
    if not 1 <= args.workers <= 64:
        raise ValueError(f"--workers must be in [1, 64], got {args.workers}")
    parse_eye(args.eye)
    methods = [m for m in args.methods.split(",") if m]
    from ..views import PROCESSING_METHODS
    if not methods or not set(methods) <= set(PROCESSING_METHODS):
        raise ValueError(f"--methods: a comma-separated subset of "
                         f"{', '.join(PROCESSING_METHODS)}, got {args.methods!r}")
    specs = scaled_specs(scale)
    work = Path(args.work) / f"scale-1_{scale.denominator}"
    res = {"scale": str(scale), "paintings": COPIES * len(specs), "workers": args.workers,
           "cpus": os.cpu_count(), "paced": not args.no_pace}
    if "build" in parts:
        res["build"], pack_path = build(args, work, specs)
        print(f"build: {res['build']['paintings']} paintings "
              f"({res['build']['stored_paintings']} stored), pack "
              f"{res['build']['pack_bytes'] / 1e9:.3f} GB, "
              f"build {res['build'].get('build_s', float('nan')):.1f} s")
    else:
        pack_path = work / "hall40.pack"
    if parts & {"multi", "hall"}:
        pack = TilePack(pack_path)
        if "multi" in parts:
            res["multi"] = multi(args, pack, specs)
            for r in res["multi"]:
                print(f"multi {r['method']}: {r['fps']:.1f} fps, processing "
                      f"{r['processing_ms']:.3f} ms, hit rate {r['hit_rate']:.3f}, "
                      f"{r['loaded_per_frame']:.1f} tiles loaded a frame")
        if "hall" in parts:
            res["hall"] = hall(args, pack, specs, scale)
            r = res["hall"]
            print(f"hall walk: {r['fps']:.1f} fps, processing {r['processing_ms']:.3f} ms, "
                  f"hit rate {r['hit_rate']:.3f}, {r['loaded_per_frame']:.1f} tiles loaded a "
                  "frame")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, json.dumps(res, indent=1) + "\n")
    print(f"results: {out}")
    return 0

"""`gigascroll bench bc1`: the bc1 (DXT1) codec against the raw pack of the same paintings.

- quality: the eight VT-mobile-VR Table 4 paintings (built-in ink landscapes, one seed each) at
  1/--scale of their size, packed raw and bc1; per painting and level, PSNR and mean FLIP
  (NVIDIA's flip-evaluator, LDR, 67 pixels per degree) of the bc1 level (assembled from the
  decoded tiles' payloads) against the raw level.
- sampling: the same resident tiles in an RGB8 cache and a BC1 cache (which decodes each
  footprint's four texels on the fly), sampled at the same points; the cost ratio bc1 / raw
  (alternating, best of --repeat, random and raster points, bilinear and trilinear).
- hit rate: the `single` scenario's walk (40 cm from the scroll, 1 m/s, magnifier on, hash
  processing, direct loading, threshold 16) over a --hit-size painting on the wall, with the
  cache at the same memory for raw (S x S slots of RGB8) and bc1 (S x 6S slots of BC1 blocks);
  loads are waited for each frame, so the rates are deterministic and differ only by the
  cache's capacity.
The loader's tiles/s on a bc1 pack are `gigascroll bench loader --codecs raw,zstd,bc1`."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import write_json


def add_arguments(p) -> None:
    p.add_argument("--scale", type=int, default=16, help="Table 4 sizes divided by this (default 16)")
    p.add_argument("--paintings", type=int, default=8, help="how many Table 4 paintings (default 8)")
    p.add_argument("--fit", default="range", choices=["range", "cluster"], help="bc1 encoder fit")
    p.add_argument("--samples", type=int, default=2_000_000, help="sampling: points per run")
    p.add_argument("--repeat", type=int, default=5, help="sampling: alternating rounds (best kept)")
    p.add_argument("--hit-size", default="12000x1600", help="hit rate: painting WxH")
    p.add_argument("--hit-slots", default="6,8,12,16", help="hit rate: raw cache sides S")
    p.add_argument("--hit-duration", type=float, default=0.6, help="hit rate: walk seconds")
    p.add_argument("--parts", default="quality,sampling,hits", help="what to run")
    p.add_argument("--cache", default="build/bench-cache", help="where packs are kept")
    p.add_argument("--out", default="build/bench/bc1", help="JSON output directory")
    p.add_argument("--quick", action="store_true", help="tiny sizes (a smoke run)")


def _packs(cache: Path, key: str, images, fit: str):
    """(raw, bc1) packs of `images()` (cached)."""
    from ..pack import TilePack, build_pack
    out = []
    for codec in ("raw", "bc1"):
        path = cache / f"{key}-{codec}{'-' + fit if codec == 'bc1' else ''}.pack"
        try:
            out.append(TilePack(path))
            continue
        except OSError:
            pass
        out.append(build_pack(images(), path, codec=codec, bc1_fit=fit, force=True, progress=True,
                              names=None))
    return out


def _level(pack, p: int, level: int) -> np.ndarray:
    from ..export import level_bands
    w, h = pack.paintings[p].level_sizes[level]
    img = np.empty((h, w, 3), np.uint8)
    for y0, band in level_bands(pack, p, level):
        img[y0:y0 + band.shape[0]] = band
    return img


def run_quality(cache: Path, args) -> list[dict]:
    import flip_evaluator
    from tqdm import tqdm

    from ..pack import render_ink_landscape
    from ..views import TABLE4_PAINTINGS
    specs = TABLE4_PAINTINGS[:args.paintings]
    sizes = [(max(s.width // args.scale, 8), max(s.height // args.scale, 8)) for s in specs]

    def images():
        return [render_ink_landscape(w, h, 0, h, i) for i, (w, h) in enumerate(sizes)]
    key = f"table4-{args.paintings}-div{args.scale}"
    raw, bc1 = _packs(cache, key, images, args.fit)
    rows = []
    jobs = [(p, l) for p in range(len(sizes)) for l in range(raw.paintings[p].levels)]
    for p, l in tqdm(jobs, desc="quality", unit="level"):
        a, b = _level(raw, p, l), _level(bc1, p, l)
        mse = float(np.mean((a.astype(np.float64) - b) ** 2))
        psnr = float("inf") if mse == 0 else 10 * math.log10(255 ** 2 / mse)
        flip = float("nan")
        if min(a.shape[:2]) >= 8:  # FLIP's filters need a few texels
            _, flip, _ = flip_evaluator.evaluate(a.astype(np.float32) / 255, b.astype(np.float32) / 255,
                                                "LDR", applyMagma=False)
        rows.append({"painting": specs[p].name, "size": list(sizes[p]), "level": l,
                     "level_size": [a.shape[1], a.shape[0]], "psnr_db": psnr, "flip": float(flip)})
    return rows


def run_sampling(cache: Path, args) -> dict:
    from ..pack import render_ink_landscape
    from ..runtime import VirtualTexture
    w, h = (4096, 1024) if args.quick else (16384, 4096)
    raw, bc1 = _packs(cache, f"ink-{w}x{h}-s0", lambda: render_ink_landscape(w, h, 0, h, 0),
                      args.fit)
    p = raw.paintings[0]
    P = raw.payload
    win = min(24, p.level_tiles[0][0], p.level_tiles[0][1])
    vts = {"raw": VirtualTexture(raw, (30, 30)), "bc1": VirtualTexture(bc1, (30, 30))}
    for level in (1, 0):
        nx, ny = (min(-(-win // 2 ** level), t) for t in p.level_tiles[level])
        for ty in range(ny):
            for tx in range(nx):
                vts["raw"].insert((0, level, tx, ty), raw.read_tile(0, level, tx, ty))
                vts["bc1"].insert((0, level, tx, ty), bc1.read_slot_tile(0, level, tx, ty))
    umax, vmax = win * P / p.width, win * P / p.height
    rng = np.random.default_rng(1)
    n = args.samples
    side = int(math.sqrt(n))
    gu, gv = np.meshgrid((np.arange(side) + 0.5) / side * umax, (np.arange(side) + 0.5) / side * vmax)
    patterns = {"random": (rng.random(n) * umax, rng.random(n) * vmax), "raster": (gu.ravel(), gv.ravel())}
    out = {"painting": f"{w}x{h}", "window_tiles": win, "samples": n, "rows": []}
    for pattern, (u, v) in patterns.items():
        for filt, lod in (("bilinear", np.zeros(u.size, np.float32)),
                          ("trilinear", rng.random(u.size).astype(np.float32))):
            t = {k: float("inf") for k in vts}
            for _ in range(args.repeat):  # alternate: load on a shared machine hits both
                for k, vt in vts.items():
                    t0 = time.perf_counter()
                    vt.sample(0, u, v, lod, filt, 1)
                    t[k] = min(t[k], time.perf_counter() - t0)
            out["rows"].append({"pattern": pattern, "filter": filt, "threads": 1,
                                "raw_samples_per_s": u.size / t["raw"],
                                "bc1_samples_per_s": u.size / t["bc1"],
                                "cost_ratio": t["bc1"] / t["raw"]})
    return out


def run_hits(cache: Path, args) -> dict:
    from .. import views as v
    from ..experiments import cached_pack
    from ..walk.frame_loop import FrameLoop
    from ..pack import render_ink_landscape
    w, h = (int(x) for x in args.hit_size.lower().split("x"))
    raw, bc1 = _packs(cache, f"ink-{w}x{h}-s0", lambda: render_ink_landscape(w, h, 0, h, 0),
                      args.fit)
    ex = v.single_scroll(v.spec_of("hits", w, h))
    path = v.scroll_path(distance=0.40, speed=1.0, duration=args.hit_duration, start_x=0.1,
                         exhibition=ex, stop_frames=10)
    rows = []
    for s in (int(x) for x in args.hit_slots.split(",")):
        row = {"raw_slots": [s, s], "bc1_slots": [s, 6 * s],
               "cache_bytes": s * s * raw.slot_bytes}
        for name, pack, slots in (("raw", raw, (s, s)), ("bc1", bc1, (s, 6 * s))):
            try:
                loop = FrameLoop(ex, pack, path, method="hash", strategy="direct", per_frame=16,
                                 slots=slots, pace=False, wait_loads=True)
                summary = loop.run()
                row[f"{name}_hit_rate"] = summary["hit_rate"]
            except ValueError as e:  # too few slots for the pinned tiles
                row[f"{name}_hit_rate"] = None
                row[f"{name}_error"] = str(e)
        rows.append(row)
        print(f"hit rate at {row['cache_bytes'] / 2**20:.1f} MiB: raw {s}x{s} "
              f"{row['raw_hit_rate']}, bc1 {s}x{6 * s} {row['bc1_hit_rate']}", flush=True)
    return {"painting": f"{w}x{h}", "frames": len(path), "rows": rows}


def run(args) -> int:
    if args.quick:
        args.scale, args.paintings, args.samples, args.repeat = 64, 2, 100_000, 2
        args.hit_size, args.hit_slots, args.hit_duration = "3000x600", "4,6", 0.1
    if args.scale < 1 or args.paintings < 1 or args.samples < 1 or args.repeat < 1:
        raise UserError("--scale, --paintings, --samples and --repeat must be positive")
    parts = {p.strip() for p in args.parts.split(",")}
    if not parts or parts - {"quality", "sampling", "hits"}:
        raise UserError("--parts must list quality, sampling and/or hits")
    cache, out = Path(args.cache), Path(args.out)
    cache.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    result = {"fit": args.fit, "ratio_slots_per_byte": 6.0}
    if "quality" in parts:
        result["quality"] = run_quality(cache, args)
        for r in result["quality"]:
            print(f"{r['painting']:18s} {r['size'][0]}x{r['size'][1]} level {r['level']:2d}: "
                  f"PSNR {r['psnr_db']:6.2f} dB  FLIP {r['flip']:.4f}", flush=True)
    if "sampling" in parts:
        result["sampling"] = run_sampling(cache, args)
        for r in result["sampling"]["rows"]:
            print(f"sampling {r['pattern']:6s} {r['filter']:9s}: raw {r['raw_samples_per_s'] / 1e6:6.1f} "
                  f"M/s  bc1 {r['bc1_samples_per_s'] / 1e6:6.1f} M/s  cost bc1/raw {r['cost_ratio']:.2f}",
                  flush=True)
    if "hits" in parts:
        result["hits"] = run_hits(cache, args)
    write_json(out / "bc1.json", result)
    print(f"wrote {out / 'bc1.json'}")
    return 0

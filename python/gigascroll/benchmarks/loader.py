"""`gigascroll bench loader`: VT-mobile-VR Table 1 (loading 50,000 tiles, lock-free vs locked),
the physical limit of the same bytes, and VT sampling cost against a plain mip texture.

Workload (VT-mobile-VR §5.1): the built-in 152089 x 6083 painting, 12 m x 0.48 m on the wall
(texel 12 m / 152089); a camera 10 cm in front of it moves head to tail at 1 m/s and loops.
Each frame's request set is computed geometrically: the tiles of the level whose texel matches
the camera's pixel footprint (pinhole camera facing the wall: footprint d / f everywhere) that
the view rectangle touches. The field of view (66 degrees by default, 1832 pixels across)
gives about 220 requests per frame, the seed's figure. Every frame (at 90 Hz) the set is
copied 10x into the loader, unless more than two frames' worth of commands are still
waiting (a fresh set replaces a stale one, as in the seed); the main thread drains finished
tiles every half millisecond and discards the data. The clock stops at the 50,000th tile.

The physical limit is a single thread reading the same number of stored bytes sequentially
from the tile file (pread, 1 MiB chunks); both run from the page cache (the pack is read once
beforehand), so the comparison is about the loaders' overhead, not the disk. "direct" is one
thread calling TilePack.read_tile on the same tile sequence with no queues or threads: the
per-tile work (read, checksum, zstd decode) the loaders parallelise. For a zstd pack,
"decode limit" is the codec's own speed on the same frames: one thread decompressing the
tile sequence's stored frames from memory with the libzstd the core links (through ctypes,
one reused ZSTD_DCtx, into one buffer), the most a loader thread could reach. A bc1 pack's loader only reads and verifies: its tiles stay blocks.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import TEXEL_M, pyplot, save_figure, timed, write_json

SEED_TABLE1 = {"locked:1": 11.45, "locked:2": 10.5, "locked:3": 10.51, "locked:4": 10.87,
               "lockfree:1": 4.81}
DEFAULT_CONFIGS = "locked:1,locked:2,locked:3,locked:4,lockfree:1,lockfree:2"


def add_arguments(p) -> None:
    p.add_argument("--width", type=int, default=152089, help="painting width (default 152089)")
    p.add_argument("--height", type=int, default=6083, help="painting height (default 6083)")
    p.add_argument("--seed", type=int, default=0, help="built-in painting variation")
    p.add_argument("--tiles", type=int, default=50000, help="tiles to load per run (default 50000)")
    p.add_argument("--configs", default=DEFAULT_CONFIGS,
                   help=f"mode:threads list (default {DEFAULT_CONFIGS})")
    p.add_argument("--codecs", default="raw,zstd", help="packs to test: raw, zstd, bc1 "
                   "(default raw,zstd)")
    p.add_argument("--repeat", type=int, default=3, help="rounds over all configurations; medians reported")
    p.add_argument("--fps", type=float, default=90.0)
    p.add_argument("--copies", type=int, default=10, help="copies of each frame's command set")
    p.add_argument("--distance", type=float, default=0.10, help="camera distance in m")
    p.add_argument("--speed", type=float, default=1.0, help="camera speed in m/s")
    p.add_argument("--fov", type=float, default=66.0, help="field of view in degrees")
    p.add_argument("--pixels", type=int, default=1832, help="pixels across the field of view")
    p.add_argument("--pool", type=int, default=256, help="loader buffer pool, in tiles")
    p.add_argument("--samples", type=int, default=4_000_000, help="VT sampling: samples per run")
    p.add_argument("--sample-size", default="16384x4096", help="VT sampling painting WxH")
    p.add_argument("--cache", default="build/bench-cache", help="where synthesized data is kept")
    p.add_argument("--out", default="build/bench/loader", help="JSON and PNG output directory")
    p.add_argument("--parts", default="loading,sampling",
                   help="what to run: loading and/or sampling (default both)")
    p.add_argument("--quick", action="store_true",
                   help="small painting and counts (a smoke run, seconds)")


# ----------------------------------------------------------------------------- data

def _painting_rgb(cache: Path, width: int, height: int, seed: int) -> np.ndarray:
    """The built-in painting as a cached raw RGB file, memory-mapped (rendered once)."""
    from ..pack import render_ink_landscape
    path = cache / f"ink-{width}x{height}-s{seed}.rgb"
    shape = (height, width, 3)
    if path.exists() and path.stat().st_size == height * width * 3:
        return np.memmap(path, np.uint8, "r", shape=shape)
    from tqdm import tqdm
    tmp = path.with_suffix(".tmp")
    out = np.memmap(tmp, np.uint8, "w+", shape=shape)
    band = 128
    with tqdm(total=height, unit="row", desc=f"render {width}x{height}") as bar:
        for y in range(0, height, band):
            rows = min(band, height - y)
            out[y:y + rows] = render_ink_landscape(width, height, y, rows, seed)
            bar.update(rows)
    out.flush()
    del out
    os.replace(tmp, path)
    return np.memmap(path, np.uint8, "r", shape=shape)


def _pack(cache: Path, width: int, height: int, seed: int, codec: str):
    """A cached pack of the built-in painting (built from the cached RGB on first use)."""
    from ..pack import TilePack, build_pack
    path = cache / f"ink-{width}x{height}-s{seed}-{codec}.pack"
    if path.exists():
        try:
            return TilePack(path)
        except OSError:
            pass  # incomplete or stale: rebuild
    rgb = _painting_rgb(cache, width, height, seed)
    return build_pack(rgb, path, codec=codec, force=True, progress=True,
                      names=[f"ink landscape {width}x{height} seed {seed}"])


def _warm(pack) -> None:
    """Reads the tile files once so every measurement runs from the page cache."""
    buf = bytearray(8 << 20)
    for name in pack.tile_files:
        with open(Path(pack.path) / name, "rb", buffering=0) as f:
            while f.readinto(buf):
                pass


# ----------------------------------------------------------------------------- requests

def frame_requests(pack, args, frame: int) -> np.ndarray:
    """(n, 4) keys the camera sees in this frame (see the module docstring)."""
    p = pack.paintings[0]
    P = pack.payload
    wall_w = p.width * TEXEL_M
    half = args.distance * math.tan(math.radians(args.fov) / 2)
    cx = (frame / args.fps * args.speed) % wall_w
    cy = p.height * TEXEL_M / 2
    footprint = 2 * half / args.pixels  # m per pixel, the same everywhere on the wall
    level = min(max(int(math.floor(math.log2(footprint / TEXEL_M))), 0), p.levels - 1)
    texel = TEXEL_M * 2 ** level
    nx, ny = p.level_tiles[level]
    x0 = max(int((cx - half) / texel // P), 0)
    x1 = min(int((cx + half) / texel // P), nx - 1)
    y0 = max(int((cy - half) / texel // P), 0)
    y1 = min(int((cy + half) / texel // P), ny - 1)
    tx, ty = np.meshgrid(np.arange(x0, x1 + 1), np.arange(y0, y1 + 1))
    n = tx.size
    return np.stack([np.zeros(n, np.int64), np.full(n, level, np.int64),
                     tx.ravel(), ty.ravel()], axis=1)


def run_loader(pack, mode: str, threads: int, args, frames: list[np.ndarray]) -> float:
    """Seconds until args.tiles tiles are loaded (frame-paced submission, data discarded)."""
    from ..runtime import TileLoader
    period = 1.0 / args.fps
    loaded = 0
    with TileLoader(pack, mode, threads, queue_capacity=4096, pool_tiles=args.pool) as loader:
        frame = 0
        per_frame = 0
        t0 = time.perf_counter()
        next_frame = t0
        while loaded < args.tiles:
            now = time.perf_counter()
            if now >= next_frame:
                cmds = np.tile(frames[frame % len(frames)], (args.copies, 1))
                per_frame = max(per_frame, len(cmds))
                s = loader.stats()
                if s["submitted"] - s["loaded"] - s["failed"] < 2 * per_frame:
                    loader.submit(cmds)
                frame += 1
                next_frame += period
            ok, failed = loader.discard()
            if failed:
                raise OSError(f"{failed} tiles failed to load from {pack.path}")
            loaded += ok
            if loaded < args.tiles:
                time.sleep(0.0005)
        elapsed = time.perf_counter() - t0
    return elapsed


def run_physical(pack, nbytes: int) -> float:
    """Seconds to read nbytes of the (one painting's) tile file sequentially in 1 MiB chunks
    (wrapping around)."""
    path = Path(pack.path) / pack.tile_files[0]
    buf = bytearray(1 << 20)
    fd = os.open(path, os.O_RDONLY)
    try:
        t0 = time.perf_counter()
        done, offset = 0, 0
        while done < nbytes:
            n = os.preadv(fd, [buf], offset)
            if n <= 0:
                offset = 0
                continue
            done += n
            offset += n
        return time.perf_counter() - t0
    finally:
        os.close(fd)


def run_direct(pack, frames: list[np.ndarray], tiles: int) -> float:
    """Seconds for one thread to read_tile `tiles` tiles of the frames' sequence, no loader."""
    out = np.empty((pack.tile_size, pack.tile_size, 3), np.uint8)
    keys = [tuple(map(int, k)) for f in frames for k in f]
    t0 = time.perf_counter()
    for i in range(tiles):
        pack.read_tile_into(*keys[i % len(keys)], out)
    return time.perf_counter() - t0


def run_decode_limit(pack, frames: list[np.ndarray], tiles: int) -> float:
    """Seconds for one thread to decompress `tiles` stored zstd frames of the frames' tile
    sequence, already in memory: no read, no checksum, no queue."""
    import ctypes
    import ctypes.util
    lib = ctypes.CDLL(ctypes.util.find_library("zstd") or "libzstd.so.1")
    lib.ZSTD_createDCtx.restype = ctypes.c_void_p
    lib.ZSTD_freeDCtx.argtypes = [ctypes.c_void_p]
    lib.ZSTD_decompressDCtx.restype = ctypes.c_size_t
    lib.ZSTD_decompressDCtx.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                                        ctypes.c_char_p, ctypes.c_size_t]
    lib.ZSTD_isError.argtypes = [ctypes.c_size_t]
    keys = [tuple(map(int, k)) for f in frames for k in f]
    stored = {}
    fds = {}
    try:
        for k in keys:
            if k not in stored:
                offset, length, _ = pack.locate(*k)
                file = pack.tile_file(*k)
                if file not in fds:
                    fds[file] = os.open(Path(pack.path) / file, os.O_RDONLY)
                stored[k] = os.pread(fds[file], length, offset)
    finally:
        for fd in fds.values():
            os.close(fd)
    sequence = [stored[keys[i % len(keys)]] for i in range(tiles)]
    nbytes = pack.tile_size * pack.tile_size * 3
    out = ctypes.create_string_buffer(nbytes)
    ctx = lib.ZSTD_createDCtx()
    decompress = lib.ZSTD_decompressDCtx
    try:
        t0 = time.perf_counter()
        for frame in sequence:
            n = decompress(ctx, out, nbytes, frame, len(frame))
            if n != nbytes:
                raise OSError(f"{pack.path}: a stored zstd frame did not decompress to a tile")
        return time.perf_counter() - t0
    finally:
        lib.ZSTD_freeDCtx(ctx)


# ----------------------------------------------------------------------------- sampling

def run_sampling(cache: Path, args) -> dict:
    """VT sampling vs the plain mip texture on the same points, all tiles of a 24 x 24-tile
    window (and its level-1 parents) resident; random and raster-order points."""
    from ..runtime import MipTexture, VirtualTexture
    w, h = (int(x) for x in args.sample_size.lower().split("x"))
    pack = _pack(cache, w, h, args.seed, "raw")
    p = pack.paintings[0]
    P = pack.payload
    win = min(24, p.level_tiles[0][0], p.level_tiles[0][1])
    vt = VirtualTexture(pack, (30, 30))
    for level in (1, 0):
        nx, ny = (min(-(-win // 2 ** level), t) for t in p.level_tiles[level])
        for ty in range(ny):
            for tx in range(nx):
                vt.insert((0, level, tx, ty), pack.read_tile(0, level, tx, ty))
    mip = MipTexture(pack)
    umax, vmax = win * P / p.width, win * P / p.height
    rng = np.random.default_rng(1)
    n = args.samples
    side = int(math.sqrt(n))
    gu, gv = np.meshgrid((np.arange(side) + 0.5) / side * umax, (np.arange(side) + 0.5) / side * vmax)
    patterns = {"random": (rng.random(n) * umax, rng.random(n) * vmax),
                "raster": (gu.ravel(), gv.ravel())}
    out = {"painting": f"{w}x{h}", "window_tiles": win, "samples": n, "rows": []}
    for pattern, (u, v) in patterns.items():
        for filt, lod in (("bilinear", np.zeros(u.size, np.float32)),
                          ("trilinear", rng.random(u.size).astype(np.float32))):
            for threads in (1, 2):
                fns = {"vt": lambda: vt.sample(0, u, v, lod, filt, threads),
                       "plain": lambda: mip.sample(u, v, lod, filt, threads)}
                t = {name: float("inf") for name in fns}
                for _ in range(5):  # alternate, best of 5: load on a shared machine hits both
                    for name, fn in fns.items():
                        t[name] = min(t[name], timed(fn)[0])
                res_vt, lv = vt.sample(0, u, v, lod, filt, threads)
                res_plain, _ = mip.sample(u, v, lod, filt, threads)
                assert (lv == np.floor(lod)).all() or filt == "bilinear"
                out["rows"].append({
                    "pattern": pattern, "filter": filt, "threads": threads,
                    "vt_samples_per_s": u.size / t["vt"], "plain_samples_per_s": u.size / t["plain"],
                    "cost_ratio": t["vt"] / t["plain"],
                    "max_abs_difference": float(np.abs(res_vt - res_plain).max())})
    return out


# ----------------------------------------------------------------------------- driver

def _plot(result: dict, path: Path) -> None:
    codecs = list(result["loading"])
    fig, axes = pyplot().subplots(1, len(codecs), figsize=(5.5 * len(codecs), 4), squeeze=False)
    for ax, codec in zip(axes[0], codecs):
        rows = result["loading"][codec]["rows"]
        names = [r["config"] for r in rows]
        ax.bar(names, [r["tiles_per_s"] for r in rows],
               color=["tab:blue" if r["config"].startswith("locked") else "tab:orange" for r in rows])
        phys = result["loading"][codec]["physical_tiles_per_s"]
        ax.axhline(phys, color="k", ls="--", label="physical limit (sequential read)")
        ax.axhline(phys / 2, color="gray", ls=":", label="half the physical limit")
        ax.axhline(result["loading"][codec]["direct_tiles_per_s"], color="tab:green", ls="-.",
                   label="direct read_tile, 1 thread")
        ax.set_title(f"{codec} pack: {result['tiles']} tiles")
        ax.set_ylabel("tiles / s")
        ax.tick_params(axis="x", rotation=30)
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def run(args) -> int:
    if args.quick:
        args.width, args.height, args.tiles, args.repeat = 12000, 1000, 3000, 1
        args.samples, args.sample_size = 200_000, "4096x1024"
    if args.width <= 0 or args.height <= 0 or args.tiles <= 0 or args.repeat <= 0:
        raise UserError("--width, --height, --tiles and --repeat must be positive")
    if args.fps <= 0 or args.copies <= 0 or args.distance <= 0 or not 0 < args.fov < 180:
        raise UserError("--fps, --copies, --distance must be positive and --fov in (0, 180)")
    configs = []
    for c in args.configs.split(","):
        mode, _, threads = c.strip().partition(":")
        if mode not in ("locked", "lockfree") or not threads.isdigit() or int(threads) < 1:
            raise UserError(f"bad configuration '{c}' (expected locked:N or lockfree:N)")
        configs.append((mode, int(threads)))
    parts = {p.strip() for p in args.parts.split(",")}
    if not parts or parts - {"loading", "sampling"}:
        raise UserError("--parts must list loading and/or sampling")
    codecs = [c.strip() for c in args.codecs.split(",")] if "loading" in parts else []
    if any(c not in ("raw", "zstd", "bc1") for c in codecs):
        raise UserError("--codecs must list raw, zstd and/or bc1")
    cache, out_dir = Path(args.cache), Path(args.out)
    cache.mkdir(parents=True, exist_ok=True)
    out_dir.mkdir(parents=True, exist_ok=True)

    result = {"painting": f"{args.width}x{args.height}", "tiles": args.tiles, "loading": {},
              "params": {k: getattr(args, k) for k in ("fps", "copies", "distance", "speed", "fov",
                                                       "pixels", "pool", "repeat")}}
    for codec in codecs:
        pack = _pack(cache, args.width, args.height, args.seed, codec)
        frames = [frame_requests(pack, args, f) for f in range(int(args.fps * 12.0 / args.speed) + 1)]
        mean_requests = statistics.mean(len(f) for f in frames)
        lengths = [pack.locate(*map(int, k))[1] for f in frames[:: max(len(frames) // 50, 1)] for k in f]
        nbytes = int(statistics.mean(lengths) * args.tiles)
        _warm(pack)
        # Rounds run every configuration once, so load drifting on a shared machine hits all
        # of them alike; each figure is the median over the rounds.
        runs: dict[str, list[float]] = {}
        for _ in range(args.repeat):
            runs.setdefault("physical", []).append(run_physical(pack, nbytes))
            runs.setdefault("direct", []).append(run_direct(pack, frames, args.tiles))
            if codec == "zstd":
                runs.setdefault("decode", []).append(run_decode_limit(pack, frames, args.tiles))
            for mode, threads in configs:
                runs.setdefault(f"{mode}:{threads}", []).append(
                    run_loader(pack, mode, threads, args, frames))
        phys = statistics.median(runs["physical"])
        direct = statistics.median(runs["direct"])
        rows = []
        for mode, threads in configs:
            name = f"{mode}:{threads}"
            sec = statistics.median(runs[name])
            rows.append({"config": name, "seconds": sec, "tiles_per_s": args.tiles / sec,
                         "runs": runs[name], "seed_seconds": SEED_TABLE1.get(name)})
            print(f"{codec:4s} {mode:8s} {threads} threads: {sec:7.3f} s  "
                  f"{args.tiles / sec:10.0f} tiles/s", flush=True)
        decode = statistics.median(runs["decode"]) if "decode" in runs else None
        for r in rows:
            threads = int(r["config"].split(":")[1])
            r["per_thread_of_decode_limit"] = (
                None if decode is None else r["tiles_per_s"] / threads / (args.tiles / decode))
        if decode is not None:
            print(f"{codec:4s} decode limit (1 thread, frames in memory): {decode:7.3f} s  "
                  f"{args.tiles / decode:10.0f} tiles/s", flush=True)
        result["loading"][codec] = {
            "decode_seconds": decode,
            "decode_limit_tiles_per_s": None if decode is None else args.tiles / decode,
            "requests_per_frame": mean_requests, "mean_tile_bytes": nbytes / args.tiles,
            "physical_seconds": phys, "physical_tiles_per_s": args.tiles / phys,
            "direct_seconds": direct, "direct_tiles_per_s": args.tiles / direct, "rows": rows}
        print(f"{codec:4s} physical limit: {phys:7.3f} s  {args.tiles / phys:10.0f} tiles/s "
              f"({nbytes / 2**20:.0f} MiB; {mean_requests:.0f} requests/frame)", flush=True)
        print(f"{codec:4s} direct, 1 thread: {direct:7.3f} s  {args.tiles / direct:10.0f} tiles/s",
              flush=True)

    if "sampling" in parts:
        result["sampling"] = run_sampling(cache, args)
    for r in result.get("sampling", {}).get("rows", []):
        print(f"sampling {r['pattern']:6s} {r['filter']:9s} {r['threads']} threads: VT "
              f"{r['vt_samples_per_s'] / 1e6:7.2f} M/s, plain {r['plain_samples_per_s'] / 1e6:7.2f} M/s, "
              f"cost x{r['cost_ratio']:.2f}", flush=True)
    write_json(out_dir / "loader.json", result, indent=2)
    if result["loading"]:
        _plot(result, out_dir / "loader.png")
    print(f"wrote {out_dir / 'loader.json'} and {out_dir / 'loader.png'}")
    return 0

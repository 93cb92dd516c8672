"""What the scenarios (gigascroll.scenarios) and the benchmarks (gigascroll.benchmarks) share:
test paintings at the scroll's texel size and their packs, the request-processing timing of
the four methods over a room, and the figure, JSON and timing helpers of their reports.
Scenarios and benchmarks import this module, never each other."""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import views as v
from .pack import TilePack, build_pack, synth_painting
from .views import TEXEL_M, spec_of
from .outputs import write_bytes, write_text

__all__ = ["TEXEL_M", "spec_of", "pattern_image", "width_for_tiles", "cached_pack",
           "scroll_pack", "time_processing", "painting_sweep", "pyplot", "save_figure",
           "write_json", "timed"]


# ----------------------------------------------------------------------------- paintings

def pattern_image(width: int, height: int, seed: int = 0) -> np.ndarray:
    """A cheap synthetic painting whose every tile differs (the loop measures loading and
    sampling, not the picture)."""
    yy = np.arange(height, dtype=np.int32)[:, None]
    xx = np.arange(width, dtype=np.int32)[None, :]
    img = np.empty((height, width, 3), np.uint8)
    img[..., 0] = (xx * 7 + yy + seed * 31) % 256
    img[..., 1] = (xx // 3 + yy * 5) % 256
    img[..., 2] = ((xx >> 2) ^ (yy >> 2)) % 256
    return img


def width_for_tiles(total: int, height: int) -> int:
    """The narrowest painting width whose pyramid (default tiles) of this height has at least
    `total` tiles."""
    lo, hi = 1, 65535 * 120
    while lo < hi:
        mid = (lo + hi) // 2
        lo, hi = (mid + 1, hi) if v.PaintingGeometry(mid, height).total_tiles < total else (lo, mid)
    return lo


# ----------------------------------------------------------------------------- packs

def cached_pack(cache: Path, key: str, images, progress: bool = False) -> TilePack:
    """Opens pack `key` from the cache directory, or builds it from `images()` (a callable
    returning a list of arrays or image paths). A build goes into a temporary directory
    renamed at the end, so an interrupted run leaves no pack that looks complete."""
    cache = Path(cache)
    path = cache / f"{key}.pack"
    if path.exists():
        try:
            return TilePack(str(path))
        except (OSError, ValueError) as e:
            raise OSError(f"{path}: cached pack is unreadable ({e}); delete it to rebuild") \
                from None
    cache.mkdir(parents=True, exist_ok=True)
    return build_pack(images(), path, progress=progress)


def scroll_pack(cache: Path, progress: bool = True) -> TilePack:
    """The full 152089 x 6083 built-in ink landscape (VT-mobile-VR's scroll), synthesized and
    packed on first use (several minutes), then read from the cache."""
    cache = Path(cache)
    w, h = v.SCROLL.width, v.SCROLL.height

    def images():
        tif = cache / f"ink-{w}x{h}-s0.tif"
        if not tif.exists():
            synth_painting(tif, w, h, seed=0, progress=True)
        return [str(tif)]
    return cached_pack(cache, f"ink-{w}x{h}-s0-raw", images, progress)


# ----------------------------------------------------------------------------- processing cost

def time_processing(configs, threads, repeats) -> list[dict]:
    """Per configuration (exhibition, feedback frames) and method: milliseconds per frame,
    wall time and CPU time of the whole process (all worker threads; a machine shared with
    other jobs distorts it much less). Each method runs all frames of a configuration in one
    block, as a frame loop running that method alone would (interleaving methods frame by
    frame let the flag array's megabytes evict the other methods' tables from the cache,
    charging them for the flag array's size); the whole sweep runs `repeats` times
    round-robin and we keep the median over frames of the least disturbed repeat. cpu-async
    counts submit plus waiting for its result: its work, not its latency."""
    state = []
    for ex, frames_buffers in configs:
        resident = ex.resident_set()
        procs = {m: v.make_processor(m, ex.tiles, threads) for m in v.PROCESSING_METHODS}
        state.append((resident, procs, frames_buffers))
    best = [{m: None for m in v.PROCESSING_METHODS} for _ in configs]
    frame_no = 0
    for _ in tqdm(range(repeats), desc="round-robin repeats", unit="repeat"):
        for ci, (resident, procs, frames_buffers) in enumerate(state):
            wall = {m: [] for m in procs}
            cpu = {m: [] for m in procs}
            requests = []  # distinct requests per frame, from the exact method
            for m, proc in procs.items():
                for f, bufs in enumerate(frames_buffers):
                    c0, t0 = time.process_time(), time.perf_counter()
                    r = v.run_processor(proc, bufs, resident, frame_no + f)
                    wall[m].append(time.perf_counter() - t0)
                    cpu[m].append(time.process_time() - c0)
                    if m == "basic":
                        requests.append(len(r["requests"]))
            frame_no += len(frames_buffers)
            for m in procs:
                cur = {"ms": 1e3 * statistics.median(wall[m]),
                       "cpu_ms": 1e3 * statistics.median(cpu[m]),
                       "requests": statistics.mean(requests)}
                if best[ci][m] is None or cur["cpu_ms"] < best[ci][m]["cpu_ms"]:
                    best[ci][m] = cur
    return best


def painting_sweep(counts, frames: int, repeats: int, threads: int = 0) -> list[dict]:
    """Request processing alone on the full-size room (the Table 4 paintings at full
    resolution: 0.57-2.8 million tiles for 8-40 paintings): feedback buffers along each
    route, every method timed on the same buffers (`gigascroll bench views` and
    `gigascroll scenario multi`)."""
    configs = []
    for n in tqdm(counts, desc="feedback, paintings", unit="config"):
        ex = v.multi_exhibition(n)
        path = v.multi_route(n, duration=frames / v.FPS)
        configs.append((ex, [v.feedback_buffers(ex, path, f, threads=threads)
                             for f in range(len(path))]))
    res = time_processing(configs, threads, repeats)
    return [{"paintings": n, "tiles": sum(t.total_tiles for t in ex.tiles), **r}
            for n, (ex, _), r in zip(counts, configs, res)]


# ----------------------------------------------------------------------------- reports

def pyplot():
    """matplotlib.pyplot on the file-only Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, path, **savefig) -> None:
    """Writes a figure (savefig's options, e.g. dpi) and closes it: rendered in memory, then
    written atomically (outputs.write_bytes), so a full disk leaves no truncated image."""
    import io

    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format=Path(path).suffix.lstrip(".").lower() or "png", **savefig)
    finally:
        plt.close(fig)
    write_bytes(path, buf.getvalue())


def write_json(path, data, indent: int = 1) -> None:
    """Writes JSON under a temporary name, then renames it: a file that is there is whole."""
    write_text(path, json.dumps(data, indent=indent))


def timed(fn):
    """(seconds, result) of one call of fn()."""
    t0 = time.perf_counter()
    result = fn()
    return time.perf_counter() - t0, result

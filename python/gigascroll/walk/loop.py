"""The frame loop, once: `run_frames` steps a camera path's frames through a started tile
loader, paced to the path's frame rate, and keeps each frame's record. What a frame does is
the caller's `FrameSteps`; the stages every frame shares are here:

- `load_stages`: issue (the loading strategy's tiles to the loader), drain (arrived tiles
  into the physical cache and page table) and update (the strategy learns what arrived, the
  displayed tiles become most recently used), each timed;
- `request_hit_rate`: the share of a frame's requests answered at their own level;
- `frame_summary`: what every run's summary holds (frame rate, stage times, hit rate).

Two kinds of steps run through it (VT-mobile-VR §4's loop with two displays): `FrameLoop`
(frame_loop.py), the views' experiment, which compares request-processing methods and
loading strategies and displays at the feedback's resolution; and `GalleryWalk`
(gallery_walk.py), the headset's walk, which displays each eye at full resolution through the
display pass, lit or unlit, and checks each frame against its oracle.
"""

from __future__ import annotations

import statistics
import time
from typing import Protocol

import numpy as np

from .. import runtime

__all__ = ["FrameSteps", "run_frames", "load_stages", "request_hit_rate", "frame_summary",
           "progress_bar", "end_frame"]


class FrameSteps(Protocol):
    """What `run_frames` needs of a loop: the pack it streams, its camera path, whether to
    pace, the loader it asks for, its records, and the two steps."""

    pack: object
    path: object          # a views.CameraPath: len() frames at path.fps
    pace: bool
    records: list

    def loader_options(self) -> dict: ...          # TileLoader mode and threads

    def progress_label(self) -> str: ...

    def open_state(self, loader): ...              # the run's state around a started loader

    def step(self, frame: int, state) -> tuple[dict, object]: ...  # (record, images)


def run_frames(steps: FrameSteps, progress: bool = False, on_frame=None) -> list[dict]:
    """Runs every frame of `steps.path`: opens a TileLoader on `steps.pack`, the steps' state
    around it, then per frame `steps.step(frame, state)`, whose record gets the frame's end
    time (`time_s`, seconds from the first frame's start) and joins `steps.records`;
    on_frame(frame, record, images) sees each frame before the next starts. With
    `steps.pace`, each frame ends at its boundary of the path's frame rate."""
    period = 1.0 / steps.path.fps
    steps.records = []
    bar = progress_bar(progress, len(steps.path), steps.progress_label())
    try:
        with runtime.TileLoader(steps.pack, **steps.loader_options()) as loader:
            state = steps.open_state(loader)
            start = time.perf_counter()
            for frame in range(len(steps.path)):
                rec, images = steps.step(frame, state)
                rec["time_s"] = time.perf_counter() - start
                steps.records.append(rec)
                if on_frame is not None:
                    on_frame(frame, rec, images)
                end_frame(bar, steps.pace, start, frame, period)
    finally:
        if bar is not None:
            bar.close()
    return steps.records


def frame_summary(records: list, stages) -> dict:
    """What every run's summary holds: frames, the frame rate (over the wall clock and
    from the mean frame time), the frame time's spread, each stage's mean time, the mean
    hit rate and requests per frame. records: non-empty, with time_s, total_ms,
    <stage>_ms, hit_rate and requests."""
    frame_ms = [x["total_ms"] for x in records]
    times = [x["time_s"] for x in records]
    n = len(records)
    return {
        "frames": n, "fps": (n - 1) / (times[-1] - times[0]) if n > 1 else float("nan"),
        "fps_from_frame_time": 1e3 / statistics.mean(frame_ms),
        "frame_ms_std": statistics.pstdev(frame_ms),
        **{f"{s}_ms": statistics.mean(x[f"{s}_ms"] for x in records) for s in stages},
        "hit_rate": statistics.mean(x["hit_rate"] for x in records),
        "requests_per_frame": statistics.mean(x["requests"] for x in records),
    }


def progress_bar(progress: bool, frames: int, desc: str):
    """A tqdm bar over a run's frames (None without `progress`)."""
    if not progress:
        return None
    from tqdm import tqdm
    return tqdm(total=frames, unit="frame", desc=desc)


def end_frame(bar, pace: bool, start: float, frame: int, period: float) -> None:
    """After a frame: the bar's step and, with `pace`, a sleep to the frame's end (frame
    boundaries every `period` seconds from `start`)."""
    if bar is not None:
        bar.update(1)
    if pace:
        delay = start + (frame + 1) * period - time.perf_counter()
        if delay > 0:
            time.sleep(delay)


def load_stages(t: dict, issue_tiles, vt, loader, loading, responses, wait_loads: bool,
                wait_timeout: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The issue, drain and update stages of one frame, each timed into `t`; returns
    (issued, arrived) tile keys. issue: issue_tiles() gives the tiles the loading strategy
    loads this frame, submitted to the loader. drain: the loader's finished tiles go into
    the physical cache and the page table in one C++ call (a tile that failed to load comes
    back without being inserted); with `wait_loads`, until every issued tile arrived (or
    `wait_timeout` seconds passed). update: the strategy learns what arrived, and the tiles
    the display samples (`responses`, or None) become most recently used, so the LRU evicts
    what the views left, not what they still show."""
    t0 = time.perf_counter()
    issue = issue_tiles()
    if issue.size:
        loader.submit(issue)
    t["issue"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    arrived, _ = vt.drain(loader)
    if wait_loads:
        deadline = None if wait_timeout is None else time.perf_counter() + wait_timeout
        while arrived.size < issue.size and (deadline is None or time.perf_counter() < deadline):
            time.sleep(0.0002)
            arrived = np.concatenate([arrived, vt.drain(loader)[0]])
    t["drain"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    if arrived.size:
        loading.loaded(arrived)
    if responses is not None and responses.size:
        vt.request(responses)
    t["update"] = time.perf_counter() - t0
    return issue, arrived


def request_hit_rate(truth, buffers, lookup, frame) -> tuple[float, int]:
    """(share of the distinct requests in `buffers` answered at their own level, count)."""
    s = truth.process(buffers, lookup, frame)
    n = int(s["requests"].size)
    return (float(np.mean(s["responses"] == s["requests"])) if n else 1.0), n

"""The frame loop (VT-mobile-VR §4, issue 4 §4, first version): per frame the feedback pass,
request processing, command issue, loader drain, physical-cache and page-table update, and a
display pass that samples the views through the virtual texture; the loader runs in its own
threads. Per frame it records each stage's time, the hit rate (share of this frame's
requests answered at the level asked), the request-processing latency in frames, and after
the camera stops the display latency (frames until every visible tile is resident at its
requested level).

The methods are the four request-processing methods of views.PROCESSING_METHODS and the two
baselines without a feedback pass (baselines.BASELINES: Ma VT, LOD-texture LOD mapping). For
those the rays still render the views for the display pass, so their time counts as display,
and the baseline's own determination plus the page-table lookup of its requests counts as
processing.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass, field

import numpy as np

from .. import runtime
from .. import views as v
from .._core import TilePack, VirtualTextureLookup
from ..errors import expect_type
from ..pack.reader import PurePack
from ..views.baselines import BASELINES, make_baseline

__all__ = ["FrameLoop", "LOADING_STRATEGIES", "STAGES", "METHODS", "load_stages",
           "request_hit_rate", "progress_bar", "end_frame", "frame_summary"]

METHODS = v.PROCESSING_METHODS + BASELINES

LOADING_STRATEGIES = ("direct", "mip-by-mip")
# The columns of VT-mobile-VR Table 5. The physical and page-table updates are part of "drain"
# here (VirtualTexture.drain inserts each arrived tile into both); "update" is the loading
# strategy's bookkeeping and the LRU touch of the tiles on screen.
STAGES = ("feedback", "processing", "issue", "drain", "update", "display")


@dataclass
class FrameLoop:
    """Runs a camera path over an exhibition whose painting p is painting p of `pack`.

    method: a views.PROCESSING_METHODS name; strategy: "direct" (VT-mobile-VR, at most
    `per_frame` requested tiles a frame) or "mip-by-mip" (van Waveren, same cap).
    pace: sleep to 90 Hz frame boundaries (False: run flat out, for tests).
    wait_loads: block each frame until that frame's loads arrived (deterministic tests;
    a real loop leaves it False and drains what is ready).
    magnifier_requests: False shows the magnifier but leaves its feedback out of request
    processing (to see what its requests add); `last_images` holds the last frame's display
    images (left eye, right eye[, magnifier]) as float RGB.
    magnifier_display_step: the display pass samples every n-th magnifier pixel per axis
    (its feedback stays at full 512 x 512; the eyes' display is at feedback resolution);
    the last frame is displayed in full."""
    exhibition: v.Exhibition
    pack: object
    path: v.CameraPath
    method: str = "hash"
    strategy: str = "direct"
    per_frame: int = 16
    slots: tuple[int, int] = (30, 30)
    loader_mode: str = "lockfree"
    loader_threads: int = 1
    pace: bool = True
    wait_loads: bool = False
    magnifier: bool = True
    magnifier_requests: bool = True
    magnifier_display_step: int = 2
    threads: int = 0
    records: list = field(default_factory=list, init=False)
    last_images: list = field(default_factory=list, init=False)

    def __post_init__(self):
        expect_type(self.exhibition, v.Exhibition, "FrameLoop: exhibition")
        expect_type(self.pack, (TilePack, PurePack), "FrameLoop: pack")
        if self.strategy not in LOADING_STRATEGIES:
            raise ValueError(f"unknown loading strategy {self.strategy!r}; choose from "
                             f"{', '.join(LOADING_STRATEGIES)}")
        if self.magnifier_display_step < 1:
            raise ValueError("magnifier_display_step must be >= 1")
        if self.per_frame <= 0:
            raise ValueError("per_frame (the direct-loading threshold) must be > 0")
        if self.method not in METHODS:
            raise ValueError(f"unknown request-processing method {self.method!r}; choose from "
                             f"{', '.join(METHODS)}")
        paintings = self.pack.paintings
        if len(paintings) < len(self.exhibition.tiles):
            raise ValueError(f"the pack has {len(paintings)} paintings, the exhibition shows "
                             f"{len(self.exhibition.tiles)}: a painting is missing from the pack")
        for i, t in enumerate(self.exhibition.tiles):
            p = paintings[i]
            if (p.width, p.height) != (t.width, t.height) or \
                    (self.pack.tile_size, self.pack.border) != (t.tile_size, t.border):
                raise ValueError(f"painting {i}: the pack holds {p.width} x {p.height} "
                                 f"(tile {self.pack.tile_size}, border {self.pack.border}), "
                                 f"the exhibition expects {t.width} x {t.height} "
                                 f"(tile {t.tile_size}, border {t.border})")

    def run(self, progress: bool = False) -> dict:
        vt = runtime.VirtualTexture(self.pack, self.slots)
        lookup = VirtualTextureLookup(vt)
        baseline = None
        if self.method in BASELINES:
            baseline = make_baseline(self.method, self.exhibition)
            proc = v.BasicProcessor()  # looks the baseline's requests up in the page table
        else:
            proc = v.make_processor(self.method, self.exhibition.tiles, self.threads)
        is_async = isinstance(proc, v.AsyncProcessor)
        direct = v.DirectLoading(self.per_frame) if self.strategy == "direct" else None
        mip = v.MipByMipLoading(self.per_frame) if self.strategy == "mip-by-mip" else None
        loading = direct if direct is not None else mip
        commands = np.zeros(0, np.uint64)
        truth = v.BasicProcessor()  # the exact request set, for the hit rate
        latency = 0
        period = 1.0 / self.path.fps
        self.records = []
        bar = progress_bar(progress, len(self.path), f"{self.method}/{self.strategy}")
        with runtime.TileLoader(self.pack, mode=self.loader_mode,
                                threads=self.loader_threads) as loader:
            start = time.perf_counter()
            for frame in range(len(self.path)):
                t = {}
                t0 = time.perf_counter()
                last = frame == len(self.path) - 1
                views = [v.render_view(self.exhibition.scene, cam, w, h, threads=self.threads,
                                       display_step=self._display_step(i, last))
                         for i, (cam, w, h) in enumerate(v.frame_cameras(
                             self.path, frame,
                             magnifier=v.MAGNIFIER if self.magnifier else None))]
                buffers = [d["keys"] for d in views]
                processed = buffers if self.magnifier_requests else buffers[:2]
                t["feedback"] = time.perf_counter() - t0

                t0 = time.perf_counter()
                new_set = None
                if baseline is not None:
                    own = baseline.requests(self.path, frame)
                    new_set = proc.process(own, lookup, frame)
                    # The rays above only feed the display pass for a baseline.
                    t["display_rays"] = t.pop("feedback")
                    t["feedback"] = 0.0
                elif is_async:
                    proc.submit(processed, frame)
                    results = proc.poll(lookup)
                    if results:
                        new_set = results[-1]
                        latency = frame - new_set["frame"]
                else:
                    new_set = proc.process(processed, lookup, frame)
                    latency = 0
                t["processing"] = time.perf_counter() - t0

                if new_set is not None:
                    commands = new_set["commands"]

                def issue_tiles():
                    if direct is None:
                        return mip.issue(commands, lookup)
                    if new_set is not None:
                        direct.set_commands(commands)
                    return direct.issue(lookup)
                issue, arrived = load_stages(
                    t, issue_tiles, vt, loader, loading,
                    None if new_set is None else new_set["responses"], self.wait_loads)

                t0 = time.perf_counter()
                images = [self._display(vt, d) for d in views]
                t["display"] = time.perf_counter() - t0 + t.pop("display_rays", 0.0)

                # Hit rate after this frame's updates: what the display showed. A request
                # hits when its response (finest resident tile answering it) is itself.
                hit_rate = request_hit_rate(truth, buffers, lookup, frame)
                view_hits = ([request_hit_rate(truth, [b], lookup, frame)[0] for b in buffers]
                             if frame == len(self.path) - 1 else None)
                self.last_images = images
                self.records.append({
                    "view_hit_rates": view_hits,
                    "frame": frame, **{f"{s}_ms": 1e3 * t[s] for s in STAGES},
                    "total_ms": 1e3 * sum(t.values()), "requests": hit_rate[1],
                    "hit_rate": hit_rate[0], "issued": int(issue.size),
                    "loaded": int(arrived.size), "latency_frames": latency,
                    "moving": frame + 1 < len(self.path) and not np.array_equal(
                        self.path.position[frame], self.path.position[frame + 1]),
                    "time_s": time.perf_counter() - start})
                end_frame(bar, self.pace, start, frame, period)
        if bar is not None:
            bar.close()
        return self.summary()

    def _display_step(self, view: int, last: bool) -> int:
        """The eyes are displayed at their feedback resolution, the magnifier at every
        magnifier_display_step-th pixel except on the last frame."""
        return 1 if view < 2 or last else self.magnifier_display_step

    def _display(self, vt, d) -> np.ndarray:
        """Samples the view through the virtual texture on its display grid, at the level
        the feedback asked for (so the same tiles are read): one GIL-free C++ pass over the
        view (views.display_view)."""
        return v.display_view(vt, d["keys"], d["lod"], d["uv"], d["display_step"],
                              self.threads)

    def summary(self) -> dict:
        r = self.records
        if not r:
            return {}
        # Display latency: from the first frame after the camera stopped until every visible
        # request is resident at its level.
        stop = next((i for i in range(len(r)) if not r[i]["moving"]
                     and all(not x["moving"] for x in r[i:])), None)
        display_latency = None
        if stop is not None:
            sharp = next((i for i in range(stop, len(r)) if r[i]["hit_rate"] == 1.0), None)
            display_latency = None if sharp is None else sharp - stop + 1
        return {
            **frame_summary(r, STAGES),
            "latency_frames": statistics.mean(x["latency_frames"] for x in r),
            "display_latency_frames": display_latency,
        }


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

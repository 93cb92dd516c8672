"""The views' experiment in the frame loop (VT-mobile-VR §4, issue 4 §4): `FrameLoop`'s steps,
run by loop.run_frames. Per frame the feedback pass, request processing, command issue,
loader drain, physical-cache and page-table update, and a display that samples the views
through the virtual texture at the feedback's resolution; the loader runs in its own
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
from .loop import frame_summary, load_stages, request_hit_rate, run_frames

__all__ = ["FrameLoop", "LOADING_STRATEGIES", "STAGES", "METHODS"]

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
        """Runs the path through the one frame loop (loop.run_frames); the summary."""
        run_frames(self, progress)
        return self.summary()

    def loader_options(self) -> dict:
        return {"mode": self.loader_mode, "threads": self.loader_threads}

    def progress_label(self) -> str:
        return f"{self.method}/{self.strategy}"

    def open_state(self, loader) -> "_ExperimentState":
        """The run's state around a started TileLoader: the virtual texture, the method's
        processor (or the baseline and the page-table lookup of its requests), the loading
        strategy, and what carries from frame to frame (the last commands, the latency)."""
        vt = runtime.VirtualTexture(self.pack, self.slots)
        baseline = None
        if self.method in BASELINES:
            baseline = make_baseline(self.method, self.exhibition)
            proc = v.BasicProcessor()  # looks the baseline's requests up in the page table
        else:
            proc = v.make_processor(self.method, self.exhibition.tiles, self.threads)
        direct = v.DirectLoading(self.per_frame) if self.strategy == "direct" else None
        mip = v.MipByMipLoading(self.per_frame) if self.strategy == "mip-by-mip" else None
        return _ExperimentState(vt=vt, lookup=VirtualTextureLookup(vt), loader=loader,
                                baseline=baseline, proc=proc,
                                is_async=isinstance(proc, v.AsyncProcessor), direct=direct,
                                mip=mip, truth=v.BasicProcessor())

    def step(self, frame: int, state: "_ExperimentState") -> tuple[dict, list]:
        """One frame: the feedback pass over every view, the method's request processing,
        the load stages and the display at the feedback's resolution; (record, images)."""
        s, t = state, {}
        t0 = time.perf_counter()
        last = frame == len(self.path) - 1
        views = [v.render_view(self.exhibition.scene, cam, w, h, threads=self.threads,
                               display_step=self._display_step(i, last))
                 for i, (cam, w, h) in enumerate(v.frame_cameras(
                     self.path, frame, magnifier=v.MAGNIFIER if self.magnifier else None))]
        buffers = [d["keys"] for d in views]
        t["feedback"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        new_set = self._process(frame, s, buffers if self.magnifier_requests else buffers[:2])
        if s.baseline is not None:  # the rays above only feed the display pass for a baseline
            t["display_rays"], t["feedback"] = t["feedback"], 0.0
        t["processing"] = time.perf_counter() - t0
        if new_set is not None:
            s.commands = new_set["commands"]

        def issue_tiles():
            if s.direct is None:
                return s.mip.issue(s.commands, s.lookup)
            if new_set is not None:
                s.direct.set_commands(s.commands)
            return s.direct.issue(s.lookup)
        issue, arrived = load_stages(
            t, issue_tiles, s.vt, s.loader, s.direct if s.direct is not None else s.mip,
            None if new_set is None else new_set["responses"], self.wait_loads)

        t0 = time.perf_counter()
        images = [self._display(s.vt, d) for d in views]
        t["display"] = time.perf_counter() - t0 + t.pop("display_rays", 0.0)

        # Hit rate after this frame's updates: what the display showed. A request hits when
        # its response (finest resident tile answering it) is itself.
        hit_rate = request_hit_rate(s.truth, buffers, s.lookup, frame)
        view_hits = ([request_hit_rate(s.truth, [b], s.lookup, frame)[0] for b in buffers]
                     if last else None)
        self.last_images = images
        return {
            "view_hit_rates": view_hits,
            "frame": frame, **{f"{st}_ms": 1e3 * t[st] for st in STAGES},
            "total_ms": 1e3 * sum(t.values()), "requests": hit_rate[1],
            "hit_rate": hit_rate[0], "issued": int(issue.size),
            "loaded": int(arrived.size), "latency_frames": s.latency,
            "moving": frame + 1 < len(self.path) and not np.array_equal(
                self.path.position[frame], self.path.position[frame + 1])}, images

    def _process(self, frame: int, s: "_ExperimentState", buffers: list):
        """This frame's request set from the method (None: an asynchronous processor has
        none ready); sets the state's latency in frames."""
        if s.baseline is not None:
            return s.proc.process(s.baseline.requests(self.path, frame), s.lookup, frame)
        if s.is_async:
            s.proc.submit(buffers, frame)
            results = s.proc.poll(s.lookup)
            if not results:
                return None
            s.latency = frame - results[-1]["frame"]
            return results[-1]
        s.latency = 0
        return s.proc.process(buffers, s.lookup, frame)

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


@dataclass
class _ExperimentState:
    vt: object
    lookup: object
    loader: object
    baseline: object
    proc: object
    is_async: bool
    direct: object
    mip: object
    truth: object
    commands: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint64))
    latency: int = 0

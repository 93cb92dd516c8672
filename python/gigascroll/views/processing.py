"""Tile determination: the feedback pass and the four request-processing methods (VT-mobile-VR
section 4.1; Vulkan-SVT's alive/remove lists), the loading strategies that turn command sets
into loads, and the display pass.

Request keys are 64-bit: painting << 37 | level << 32 | morton(tile x, tile y).
"""

from __future__ import annotations

import numpy as np

from .._core import (NO_REQUEST, AsyncProcessor, BasicProcessor, DirectLoading,
                     FlagArrayProcessor, HashProcessor, MipByMipLoading, PaintingGeometry,
                     ResidencyLookup, VisibilityLists, display_view, mip_level, pack_request,
                     render_view, texel_footprint, unpack_requests)
from .camera_paths import CameraPath, frame_cameras
from .exhibition import HEADSET, MAGNIFIER, Exhibition, Headset, Magnifier

__all__ = ["NO_REQUEST", "AsyncProcessor", "BasicProcessor", "DirectLoading",
           "FlagArrayProcessor", "HashProcessor", "MipByMipLoading", "ResidencyLookup",
           "VisibilityLists", "display_view", "mip_level", "pack_request", "render_view",
           "texel_footprint", "unpack_requests", "feedback_buffers", "PROCESSING_METHODS",
           "make_processor", "run_processor"]


def feedback_buffers(exhibition: Exhibition, path: CameraPath, frame: int,
                     magnifier: Magnifier | None = MAGNIFIER, threads: int = 0,
                     headset: Headset = HEADSET) -> list[np.ndarray]:
    """The frame's feedback buffers (left eye, right eye[, magnifier]) as uint64 key images."""
    return [render_view(exhibition.scene, cam, w, h, threads=threads, display=False)["keys"]
            for cam, w, h in frame_cameras(path, frame, headset, magnifier)]


PROCESSING_METHODS = ("basic", "cpu-async", "flag-array", "hash")


def make_processor(method: str, tiles: list[PaintingGeometry], threads: int = 0,
                   table_bits: int = 16):
    """A request processor by name (PROCESSING_METHODS)."""
    if method == "basic":
        return BasicProcessor()
    if method == "cpu-async":
        return AsyncProcessor()
    if method == "flag-array":
        return FlagArrayProcessor(tiles, threads)
    if method == "hash":
        return HashProcessor(table_bits, threads=threads)
    raise ValueError(f"unknown request-processing method {method!r}; "
                     f"choose from {', '.join(PROCESSING_METHODS)}")


def run_processor(processor, buffers, lookup: ResidencyLookup, frame: int) -> dict:
    """One frame through any processor; cpu-async waits for its own result (to compare sets;
    frame loops poll instead and measure the latency)."""
    if not isinstance(processor, AsyncProcessor) and not callable(getattr(processor, "process", None)):
        raise TypeError(f"run_processor: processor must be one of the request processors "
                        f"(make_processor), not {type(processor).__name__}")
    if isinstance(processor, AsyncProcessor):
        processor.submit(buffers, frame)
        results = processor.poll(lookup, wait=True)
        return results[-1]
    return processor.process(buffers, lookup, frame)

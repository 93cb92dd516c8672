"""Views and tile determination: the exhibition scene, the headset's eyes and the magnifier,
camera paths shared by scenarios and tests, the feedback pass and the four request-processing
methods (VT-mobile-VR §§4.1, 5; Vulkan-SVT's alive/remove lists), and the two baselines
without a feedback pass.

- :mod:`.exhibition`: headset, magnifier, test paintings, the wall scroll and the tables room
- :mod:`.camera_paths`: `CameraPath`, `scroll_path`, `multi_route`, `frame_cameras`
- :mod:`.processing`: feedback, request processing, loading strategies, the display pass
- :mod:`.baselines`: Ma VT and LOD-texture's LOD mapping

The frame loop that runs all of it (gigascroll.walk.frame_loop) builds on this package; nothing
here imports it.
"""

from .._core import ExhibitionScene, PaintingGeometry, ResidentSet, Camera
from . import baselines
from .camera_paths import CameraPath, frame_cameras, multi_route, scroll_path
from .exhibition import (FPS, HEADSET, MAGNIFIER, SCROLL, TABLE4_PAINTINGS, TEXEL_M, Exhibition,
                         Headset, Magnifier, PaintingSpec, multi_exhibition, single_scroll,
                         spec_of)
from .processing import (NO_REQUEST, PROCESSING_METHODS, AsyncProcessor, BasicProcessor,
                         DirectLoading, FlagArrayProcessor, HashProcessor, MipByMipLoading,
                         ResidencyLookup, VisibilityLists, display_view, feedback_buffers,
                         make_processor, mip_level, pack_request, render_view, run_processor,
                         texel_footprint, unpack_requests)

__all__ = [
    "NO_REQUEST", "AsyncProcessor", "BasicProcessor", "Camera", "DirectLoading",
    "ExhibitionScene", "FlagArrayProcessor", "MipByMipLoading", "HashProcessor", "PaintingGeometry",
    "ResidencyLookup", "ResidentSet", "VisibilityLists", "display_view", "mip_level",
    "pack_request", "render_view", "texel_footprint", "unpack_requests",
    "HEADSET", "MAGNIFIER", "SCROLL", "TABLE4_PAINTINGS", "Headset", "Magnifier", "PaintingSpec",
    "Exhibition", "CameraPath", "single_scroll", "multi_exhibition", "scroll_path",
    "multi_route", "frame_cameras", "feedback_buffers", "PROCESSING_METHODS",
    "make_processor", "run_processor",
]

# Also reachable as gigascroll.views.X, outside __all__ (not re-exported by gigascroll): FPS,
# TEXEL_M, spec_of, and the baselines module.

"""gigascroll: gigapixel paintings in VR with virtual texturing and photon mapping.

The compiled core lives in :mod:`gigascroll._core`; this package re-exports its public
classes and adds the Python-side drivers (image synthesis, pack building, scenarios).
Data flows one way: prepare (pack) -> determine (views) -> load/cache/sample (runtime)
-> the frame loop over all three (frame_loop); render (photon) lights the room.
"""

from . import _core
from ._core import hardware_threads
# tile packs: synthesis, building, reading
from .pack import (PackPainting, TilePack, build_pack, open_image, pack_manifest, pack_summary,
                   painting_geometry, plan_layout, read_level, render_ink_landscape,
                   synth_painting, to_rgb8, verify_pack)
# loader, physical cache, page table, sampling
from .runtime import LoadError, MipTexture, TileLoader, VirtualTexture
# exhibition scene, views, tile determination
from .views import (HEADSET, MAGNIFIER, NO_REQUEST, PROCESSING_METHODS, SCROLL, TABLE4_PAINTINGS,
                    AsyncProcessor, BasicProcessor, CameraPath, DirectLoading, Exhibition,
                    ExhibitionScene, FlagArrayProcessor, HashProcessor, Headset, Magnifier,
                    MipByMipLoading, PaintingSpec, PaintingGeometry, ResidencyLookup, ResidentSet,
                    Camera, VisibilityLists, display_view, feedback_buffers, frame_cameras,
                    make_processor, mip_level, multi_exhibition, multi_route, pack_request,
                    render_view, run_processor, scroll_path, single_scroll, texel_footprint,
                    unpack_requests)
# the frame loop over views and runtime
from .walk.frame_loop import LOADING_STRATEGIES, FrameLoop
# photon-mapping renderer
from .photon import (BUILTIN_SCENES, ROOMS, PhotonMap, RoomScene, Scene, StereoCamera,
                     builtin_scene, default_radius, relmse, render, render_stereo, room_scene,
                     save_image, trace_photons)
# the gallery: room and paintings in one scene, lit by the photon map
from .gallery import Gallery, PaintingSlot, RoomSpec, Surface

__version__ = "0.1.0"

__all__ = [
    "hardware_threads", "__version__",
    # pack
    "TilePack", "PackPainting", "build_pack", "open_image", "painting_geometry", "to_rgb8",
    "plan_layout", "synth_painting", "render_ink_landscape", "read_level", "pack_summary",
    "pack_manifest", "verify_pack",
    # runtime
    "TileLoader", "VirtualTexture", "MipTexture", "LoadError",
    # views
    "NO_REQUEST", "AsyncProcessor", "BasicProcessor", "Camera", "DirectLoading",
    "ExhibitionScene", "FlagArrayProcessor", "MipByMipLoading", "HashProcessor", "PaintingGeometry",
    "ResidencyLookup", "ResidentSet", "VisibilityLists", "display_view", "mip_level",
    "pack_request", "render_view", "texel_footprint", "unpack_requests", "HEADSET", "MAGNIFIER",
    "SCROLL", "TABLE4_PAINTINGS", "Headset", "Magnifier", "PaintingSpec", "Exhibition",
    "CameraPath", "single_scroll", "multi_exhibition", "scroll_path", "multi_route",
    "frame_cameras", "feedback_buffers", "PROCESSING_METHODS", "make_processor",
    "run_processor",
    # frame loop
    "FrameLoop", "LOADING_STRATEGIES",
    # photon
    "Scene", "StereoCamera", "PhotonMap", "RoomScene", "room_scene", "ROOMS", "builtin_scene", "BUILTIN_SCENES",
    "default_radius", "render", "render_stereo", "trace_photons", "save_image", "relmse",
    # gallery
    "Gallery", "RoomSpec", "Surface", "PaintingSlot",
]

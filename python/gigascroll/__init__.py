"""gigascroll: gigapixel paintings in VR with virtual texturing and photon mapping.

The compiled core lives in :mod:`gigascroll._core`; this package re-exports its public
classes and adds the Python-side drivers (image synthesis, pack building, scenarios).
Data flows one way: prepare (pack) -> determine (views) -> load/cache/sample (runtime)
-> render (photon).
"""

from . import _core
from ._core import hardware_threads
from .pack import *  # noqa: F401,F403  tile packs: synthesis, building, reading
from .runtime import *  # noqa: F401,F403  loader, physical cache, page table, sampling
from .views import *  # noqa: F401,F403  exhibition scene, views, tile determination
from .photon import *  # noqa: F401,F403  photon-mapping renderer

from . import pack as _pack, runtime as _runtime, views as _views, photon as _photon

__version__ = "0.1.0"

__all__ = ["hardware_threads", "__version__",
           *_pack.__all__, *_runtime.__all__, *_views.__all__, *_photon.__all__]

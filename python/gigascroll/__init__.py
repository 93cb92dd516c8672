"""gigascroll: gigapixel paintings in VR with virtual texturing and photon mapping.

The compiled core lives in :mod:`gigascroll._core`; this package re-exports its public
classes and adds the Python-side drivers (image synthesis, pack building, scenarios).
"""

from . import _core
from ._core import hardware_threads

__version__ = "0.1.0"

__all__ = ["hardware_threads", "__version__"]

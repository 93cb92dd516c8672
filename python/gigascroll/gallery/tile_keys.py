"""`parent_keys`: the tiles one level coarser of request keys, the second level that trilinear
filtering reads. The walk requests them beside each frame's requests; `Gallery.stream` loads
them for stills. One definition, so that a still and a walk frame read the same tiles."""

from __future__ import annotations

import numpy as np

from .. import views as v

__all__ = ["parent_keys"]


def parent_keys(keys: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """The tiles one level coarser of request keys (the second level trilinear filtering
    reads), dropping those already at a painting's coarsest level. levels: per painting id."""
    k = np.asarray(keys, np.uint64).ravel()
    k = k[k != v.NO_REQUEST]
    painting = (k >> np.uint64(37)).astype(np.int64)
    level = ((k >> np.uint64(32)) & np.uint64(0x1F)).astype(np.int64)
    keep = level + 1 < levels[painting]
    k, level = k[keep], level[keep]
    morton = k & np.uint64(0xFFFFFFFF)
    base = k & ~np.uint64((0x1F << 32) | 0xFFFFFFFF)
    return np.unique(base | ((level + 1).astype(np.uint64) << np.uint64(32))
                     | (morton >> np.uint64(2)))

"""Streaming runtime: the tile loader, the physical cache with its page table, and software
virtual-texture sampling (VT-mobile-VR §4.2-4.4, Vulkan-SVT's fallback, Mayer-VT §3.3).

Tile keys are ``(painting, level, tx, ty)``; several keys are an ``(n, 4)`` integer array or a
sequence of 4-tuples, or a 1-D uint64 array of request keys (the views' ``pack_request``
layout), which the frame loop keeps from request processing to the cache. Sampled colours
are float32 RGB in the 0..255 range of the stored tiles.
"""

from __future__ import annotations

import numpy as np

from . import _core

__all__ = ["TileLoader", "VirtualTexture", "MipTexture", "LoadError"]


class LoadError(OSError):
    """A tile the loader could not read (short file, checksum mismatch, corrupt zstd frame)."""


def _keys(keys) -> np.ndarray:
    """(n, 4) int64 from an array or a sequence of 4-tuples."""
    a = np.asarray(keys)
    if a.size == 0:
        return np.zeros((0, 4), np.int64)
    if a.dtype.kind not in "iu":
        raise ValueError(f"tile keys must be integers, got {a.dtype}")
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"tile keys must have shape (n, 4) (painting, level, tx, ty), got {a.shape}")
    return np.asarray(a, dtype=np.int64)


def _is_request_keys(keys) -> bool:
    """A 1-D uint64 array: request keys, not (painting, level, tx, ty) rows."""
    return isinstance(keys, np.ndarray) and keys.ndim == 1 and keys.dtype == np.uint64


def _uv(u, v, lod):
    """Flattened float64 u, v (same shape), lod array / scalar, and the output shape."""
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if u.shape != v.shape:
        raise ValueError(f"u and v must have the same shape, got {u.shape} and {v.shape}")
    if np.isnan(u).any() or np.isnan(v).any():
        raise ValueError("u and v must not contain NaN")
    shape = u.shape
    u, v = u.ravel(), v.ravel()
    lod_array, lod_scalar = None, 0.0
    if lod is not None:
        lod = np.asarray(lod, dtype=np.float32)
        if np.isnan(lod).any():
            raise ValueError("lod must not contain NaN")
        if lod.ndim == 0:
            lod_scalar = float(lod)
        else:
            if lod.shape != shape:
                raise ValueError(f"lod must be a scalar or have the shape of u, got {lod.shape}")
            lod_array = lod.ravel()
    return u, v, lod_array, lod_scalar, shape


def _sample(target, args, u, v, lod, filter, threads):
    u, v, lod_array, lod_scalar, shape = _uv(u, v, lod)
    out = np.empty((u.size, 3), np.float32)
    levels = np.empty(u.size, np.int8)
    _core._sample_into(target, *args, u, v, lod_array, lod_scalar, filter, out, levels, int(threads))
    return out.reshape(shape + (3,)), levels.reshape(shape)


class TileLoader(_core.TileLoader):
    """Asynchronous tile loading from a :class:`gigascroll.TilePack`.

    ``TileLoader(pack, mode="lockfree" | "locked", threads=1, queue_capacity=4096,
    pool_tiles=64)``. The main thread calls :meth:`submit` and, once per frame, :meth:`poll`
    (or :meth:`VirtualTexture.drain`); neither blocks in lock-free mode. Commands that do not fit in the queues wait in a backlog
    flushed by later calls (back-pressure, nothing is dropped). Use as a context manager, or
    call :meth:`close`.
    """

    def submit(self, keys) -> None:
        """Queues load commands, given as (n, 4) tile keys or a 1-D uint64 array of request
        keys; ValueError (nothing queued) if a key is not a tile of the pack."""
        if _is_request_keys(keys):
            self._submit_requests(keys)
        else:
            self._submit(_keys(keys))

    def poll(self, max_tiles: int | None = None) -> list:
        """Finished tiles as ``[(key, data)]``: data is a (T, T, 3) uint8 array (BC1 blocks,
        (T/4, T/4, 8), for a bc1 pack), or a
        :class:`LoadError` for a tile that could not be read."""
        n = (1 << 62) if max_tiles is None else int(max_tiles)
        if n < 0:
            raise ValueError("max_tiles must be >= 0")
        return [(key, data if isinstance(data, np.ndarray) else LoadError(data))
                for key, data in self._poll(n)]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class VirtualTexture(_core.VirtualTexture):
    """The physical tile cache of a pack with its mip-mapped page table.

    ``VirtualTexture(pack, slots=(30, 30))``: slots_x x slots_y tiles, LRU replacement; every
    tile of each painting's coarse "tail" levels (at least its single coarsest tile) is pinned,
    so every lookup has a resident answer. A bc1 pack's tiles stay BC1 blocks in the slots
    (``format`` 'bc1', ``slot_bytes`` T^2 / 2 against 3 T^2: 6x the tiles per byte), decoded
    by ``sample`` on the fly. ``drain(loader, max_tiles=2**64 - 1)`` polls the
    loader and inserts its finished tiles in C++, returning ``(arrived, failed)``: the request
    keys (1-D uint64) of every tile that came back, inserted or not, and
    ``[((painting, level, tx, ty), message), ...]`` for the loads that failed.
    """

    def insert(self, key, data: np.ndarray):
        """Copies one tile (a (T, T, 3) uint8 array, or (T/4, T/4, 8) BC1 blocks when the
        pack's codec is bc1: see ``format``) into the cache and updates
        the page table; returns the evicted tile's key, or None."""
        data = np.asarray(data)
        if data.dtype != np.uint8:
            raise ValueError(f"tile data must be uint8, got {data.dtype}")
        return super().insert(tuple(int(k) for k in key), data)

    def request(self, keys):
        """One frame's requests: resident tiles count as hits and become most recently used;
        the missing ones (misses) are returned, each once, in request order: a 1-D uint64
        array for request keys in, a list of (painting, level, tx, ty) tuples otherwise."""
        if _is_request_keys(keys):
            return self._request_keys(keys)
        return super().request(_keys(keys))

    def sample(self, painting: int, u, v, lod=None, filter: str = "bilinear", threads: int = 0):
        """Samples painting ``painting`` at uv (arrays of any shape, float64 kept exact) and
        returns ``(rgb, level)``: float32 colours of shape ``u.shape + (3,)`` and the level that
        answered (int8, >= the one asked for when that tile is not resident). ``lod`` is None
        (level 0), a scalar or an array like u; bilinear uses the nearest level, trilinear
        blends floor(lod) and floor(lod) + 1. uv outside [0, 1] clamp to the edge."""
        return _sample(self, (int(painting),), u, v, lod, filter, threads)


class MipTexture(_core.MipTexture):
    """A whole painting's mip chain in memory, sampled by the same filter code as
    :class:`VirtualTexture` without the indirection (the baseline). ``MipTexture(pack,
    painting=0, levels=0)`` assembles it from the pack's tiles (0 = all levels)."""

    def sample(self, u, v, lod=None, filter: str = "bilinear", threads: int = 0):
        """Same as :meth:`VirtualTexture.sample` without the painting (level = the one asked)."""
        return _sample(self, (), u, v, lod, filter, threads)

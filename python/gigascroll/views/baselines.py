"""Tile determination without a feedback pass: the two baselines of VT-mobile-VR Fig. 12.

- `MaVT` (Ma et al. 2024): every level-0 tile of every painting is tested on the CPU each
  frame: is its centre in front of the head and inside the field of view, and how far is it?
  Its distance along the view axis gives the level (the footprint of a display pixel on a
  plane facing the viewer at that depth, the pinhole's exact footprint for a head-on
  painting), and the tile's ancestor at that level is requested. Its cost grows with the
  tile total.
- `LodMapping` (LOD-texture): one whole mip level per painting, chosen by the viewer's distance
  to the painting with the seed's bands LOD1 <= 100, LOD2 100-200, LOD3 200-300, LOD4
  300-500 (far = 500). The seed's scene units are not ours; we scale them so that LOD1 (our
  level 0) ends where our headset stops needing level 0 on a head-on painting (footprint 2
  texels per display pixel: 14.4 cm for the scroll's 78.9 um texels), i.e. one unit =
  1.44 mm: LOD1..LOD4 = levels 0..3 up to 14.4 / 28.8 / 43.2 / 72 cm. The first two bands then
  match the feedback's levels exactly, LOD3 and LOD4 are finer than needed. Beyond the far
  plane the painting takes its coarsest level. Every tile of the chosen level is requested:
  `memory_bytes` reports what that costs.

Both return request keys (views' pack_request layout) that go through the same request
processing (the basic method as a lookup) and loading as the feedback-based methods.
"""

from __future__ import annotations

import math

import numpy as np

from .camera_paths import CameraPath
from .exhibition import HEADSET, TEXEL_M, Exhibition, Headset

__all__ = ["BASELINES", "MaVT", "LodMapping", "make_baseline", "LOD_BANDS_M"]

BASELINES = ("ma-vt", "lod-mapping")
# LOD-texture's bands (scene units 100, 200, 300, 500), scaled so that LOD1 ends where a
# head-on view of the scroll's texels stops needing level 0: 2 texels per display pixel.
_LEVEL0_END_M = 2 * TEXEL_M / (2 * HEADSET.tan_half_x / HEADSET.width)
LOD_BANDS_M = tuple(_LEVEL0_END_M * b / 100 for b in (100, 200, 300, 500))


def _placements(exhibition: Exhibition):
    for p, pl in enumerate(exhibition.placements):
        yield (p, exhibition.tiles[p], np.asarray(pl["origin"], float),
               np.asarray(pl["u_axis"], float), np.asarray(pl["v_axis"], float),
               exhibition.specs[p])


class MaVT:
    """Per-tile distance test over all level-0 tiles (Ma VT)."""

    def __init__(self, exhibition: Exhibition, headset: Headset = HEADSET):
        self.headset = headset
        self.paintings = []
        for p, tiles, origin, u, vax, spec in _placements(exhibition):
            P = tiles.payload
            tx, ty = np.meshgrid(np.arange(tiles.tiles_x(0)), np.arange(tiles.tiles_y(0)))
            tx, ty = tx.ravel().astype(np.uint32), ty.ravel().astype(np.uint32)
            # Tile centres in metres along the painting's axes (clamped to the real extent).
            cu = np.minimum((tx + 0.5) * P, tiles.width) / tiles.width * spec.width_m
            cv = np.minimum((ty + 0.5) * P, tiles.height) / tiles.height * spec.height_m
            centres = origin + cu[:, None] * u + cv[:, None] * vax
            self.paintings.append((p, tiles, tx, ty, centres, spec.width_m / tiles.width))

    @property
    def tile_total(self) -> int:
        return sum(len(t[2]) for t in self.paintings)

    def requests(self, path: CameraPath, frame: int) -> np.ndarray:
        pos, fwd, up = path.position[frame], path.forward[frame], path.up[frame]
        fwd = fwd / np.linalg.norm(fwd)
        right = np.cross(fwd, up)
        right /= np.linalg.norm(right)
        upv = np.cross(right, fwd)
        h = self.headset
        # Angle of one display pixel on the view axis.
        pixel = 2 * h.tan_half_x / h.width
        keys = []
        for p, tiles, tx, ty, centres, texel in self.paintings:
            d = centres - pos
            z = d @ fwd
            ok = z > 1e-6
            zz = np.where(ok, z, 1.0)
            # A tile whose centre is outside the view is still needed if the view sees part of
            # it: widen the test by half a tile's size at that depth (and by half the IPD
            # sideways: the eyes sit +-ipd/2 from the head).
            slack = 0.5 * tiles.payload * texel / zz
            ok &= np.abs(d @ right) / zz <= h.tan_half_x + slack + 0.5 * h.ipd / zz
            ok &= np.abs(d @ upv) / zz <= h.tan_half_y + slack
            if not ok.any():
                continue
            footprint = z[ok] * pixel / texel  # texels per display pixel, head-on
            level = np.clip(np.floor(np.log2(np.maximum(footprint, 1.0))), 0,
                            tiles.levels - 1).astype(np.uint32)
            x, y = tx[ok] >> level, ty[ok] >> level
            keys.append((np.uint64(p) << np.uint64(37)) | (level.astype(np.uint64)
                        << np.uint64(32)) | _morton(x, y))
        if not keys:
            return np.zeros(0, np.uint64)
        return np.unique(np.concatenate(keys))


class LodMapping:
    """LOD-texture: one whole level per painting by viewer distance."""

    def __init__(self, exhibition: Exhibition, bands=LOD_BANDS_M):
        if any(not (b > 0 and math.isfinite(b)) for b in bands) or list(bands) != sorted(bands):
            raise ValueError("LOD distance bands must be positive, finite and increasing")
        self.bands = tuple(bands)
        self.paintings = [(p, tiles, origin, u, vax, spec)
                          for p, tiles, origin, u, vax, spec in _placements(exhibition)]
        self._level_keys = {}

    def level_of(self, distance: float, levels: int) -> int:
        for lvl, b in enumerate(self.bands):
            if distance <= b:
                return min(lvl, levels - 1)
        return levels - 1  # beyond the far plane: the coarsest level

    def distances(self, position) -> list[float]:
        """Distance from `position` to the nearest point of each painting rectangle."""
        out = []
        for p, tiles, origin, u, vax, spec in self.paintings:
            d = np.asarray(position, float) - origin
            a = np.clip(d @ u, 0.0, spec.width_m)
            b = np.clip(d @ vax, 0.0, spec.height_m)
            out.append(float(np.linalg.norm(d - a * u - b * vax)))
        return out

    def chosen_levels(self, path: CameraPath, frame: int) -> list[int]:
        return [self.level_of(dist, pl[1].levels) for dist, pl in
                zip(self.distances(path.position[frame]), self.paintings)]

    def _keys(self, p: int, tiles, level: int) -> np.ndarray:
        k = (p, level)
        if k not in self._level_keys:
            tx, ty = np.meshgrid(np.arange(tiles.tiles_x(level), dtype=np.uint32),
                                 np.arange(tiles.tiles_y(level), dtype=np.uint32))
            self._level_keys[k] = ((np.uint64(p) << np.uint64(37)) |
                                   (np.uint64(level) << np.uint64(32)) |
                                   _morton(tx.ravel(), ty.ravel()))
        return self._level_keys[k]

    def requests(self, path: CameraPath, frame: int) -> np.ndarray:
        levels = self.chosen_levels(path, frame)
        return np.concatenate([self._keys(pl[0], pl[1], lvl)
                               for pl, lvl in zip(self.paintings, levels)])

    def memory_bytes(self, path: CameraPath, frame: int, tile_bytes: int) -> int:
        """Texture memory of the whole levels chosen at this frame."""
        return int(sum(pl[1].tile_count(lvl) for pl, lvl in
                       zip(self.paintings, self.chosen_levels(path, frame))) * tile_bytes)


def _morton(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    def spread(a):
        a = a.astype(np.uint64) & np.uint64(0xFFFF)
        for shift, mask in ((8, 0x00FF00FF), (4, 0x0F0F0F0F), (2, 0x33333333), (1, 0x55555555)):
            a = (a | (a << np.uint64(shift))) & np.uint64(mask)
        return a
    return spread(x) | (spread(y) << np.uint64(1))


def make_baseline(name: str, exhibition: Exhibition):
    if name == "ma-vt":
        return MaVT(exhibition)
    if name == "lod-mapping":
        return LodMapping(exhibition)
    raise ValueError(f"unknown baseline {name!r}; choose from {', '.join(BASELINES)}")

"""Independent references for the pack tests: exact mip levels and bordered tiles computed
in numpy, the check of a whole painting against them, test images."""

import numpy as np
import OpenImageIO as oiio
import pytest

from gigascroll import TilePack


def ref_level(img: np.ndarray, level: int) -> np.ndarray:
    """Exact mean of the real level-0 pixels under each level-l texel (float64), computed
    directly from level 0 with reduceat, not by repeated halving."""
    s = 1 << level
    h, w = img.shape[:2]
    rows = np.arange(0, h, s)
    cols = np.arange(0, w, s)
    sums = np.add.reduceat(np.add.reduceat(img.astype(np.float64), rows, axis=0), cols, axis=1)
    ch = np.minimum(rows + s, h) - rows
    cw = np.minimum(cols + s, w) - cols
    return sums / (ch[:, None, None] * cw[None, :, None])


def ref_tile(level_img: np.ndarray, tx: int, ty: int, tile: int, border: int) -> np.ndarray:
    payload = tile - 2 * border
    h, w = level_img.shape[:2]
    ys = np.clip(np.arange(ty * payload - border, ty * payload - border + tile), 0, h - 1)
    xs = np.clip(np.arange(tx * payload - border, tx * payload - border + tile), 0, w - 1)
    return level_img[ys][:, xs]


def check_pack_against(pack: TilePack, index: int, img: np.ndarray):
    """Every stored tile of painting `index` matches the reference within the 8-bit rounding
    of the exact average; padding tiles are absent; geometry and UV scale are right."""
    T, b = pack.tile_size, pack.border
    P = T - 2 * b
    p = pack.paintings[index]
    h, w = img.shape[:2]
    assert (p.width, p.height) == (w, h)
    Mp, Np = p.table_size
    assert Mp & (Mp - 1) == 0 and Np & (Np - 1) == 0
    assert Mp >= -(-w // P) > Mp // 2 or Mp == 1
    assert Np >= -(-h // P) > Np // 2 or Np == 1
    assert p.uv_scale == pytest.approx((w / (Mp * P), h / (Np * P)))
    # Levels stop at the first one that fits in a single tile.
    last_w, last_h = p.level_sizes[-1]
    assert last_w <= P and last_h <= P
    if p.levels > 1:
        assert max(p.level_sizes[-2]) > P
    for level in range(p.levels):
        ref = ref_level(img, level)
        lh, lw = ref.shape[:2]
        assert p.level_sizes[level] == (lw, lh)
        nx, ny = -(-lw // P), -(-lh // P)
        assert p.level_tiles[level] == (nx, ny)
        gx, gy = max(1, Mp >> level), max(1, Np >> level)
        for ty in range(gy):
            for tx in range(gx):
                if tx >= nx or ty >= ny:
                    assert not pack.has_tile(index, level, tx, ty)
                    continue
                assert pack.has_tile(index, level, tx, ty)
                tile = pack.read_tile(index, level, tx, ty)
                assert tile.shape == (T, T, 3) and tile.dtype == np.uint8
                err = np.abs(tile - ref_tile(ref, tx, ty, T, b))
                assert err.max() <= 0.5 + 1e-9, (level, tx, ty, err.max())
        with pytest.raises(ValueError):
            pack.has_tile(index, level, gx, 0)
        with pytest.raises(ValueError):
            pack.read_tile(index, level, 0, gy)


def noise(h, w, c=3, dtype=np.uint8, seed=0):
    rng = np.random.default_rng(seed)
    if dtype == np.uint8:
        a = rng.integers(0, 256, (h, w, c), dtype=np.uint8)
    elif dtype == np.uint16:
        a = rng.integers(0, 65536, (h, w, c), dtype=np.uint16)
    else:
        a = rng.random((h, w, c), dtype=np.float32) * 1.2 - 0.1
    return a[:, :, 0] if c == 0 else a


def write_image(path, pixels):
    """Writes pixels as stored values (alpha unassociated, so colours are not divided by it)."""
    pixels = np.ascontiguousarray(pixels)
    fmt = {np.dtype(np.uint8): oiio.UINT8, np.dtype(np.uint16): oiio.UINT16,
           np.dtype(np.float32): oiio.FLOAT}[pixels.dtype]
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], fmt)
    spec.attribute("oiio:UnassociatedAlpha", 1)
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(pixels), out.geterror()
    out.close()

"""The bc1 codec end to end: stored blocks decoded by a numpy reference of the BC1 format
written here (and by the pure-Python reader) against the core's decoder, bit for bit; the
loader and the cache keep the blocks; sampling across tile seams against the raw pack of the
same image within a bound derived from the texels; the CLI's --codec bc1."""

import numpy as np
import pytest

from gigascroll import build_pack
from gigascroll.pack import TilePack
from gigascroll.pack.reader import PurePack, decode_bc1
from gigascroll.runtime import TileLoader, VirtualTexture

W, H, T, B = 300, 170, 32, 4  # payload 24


def reference_bc1(blocks: np.ndarray) -> np.ndarray:
    """BC1 by the format's definition, one block at a time (slow, obvious): RGB565 endpoints
    widened by bit replication; c0 > c1: c0, c1, (2 c0 + c1) // 3, (c0 + 2 c1) // 3, else
    c0, c1, (c0 + c1) // 2, black; texel (x, y) takes bits 2x..2x+1 of index byte y."""
    by, bx = blocks.shape[:2]
    out = np.zeros((4 * by, 4 * bx, 3), np.uint8)
    for j in range(by):
        for i in range(bx):
            b = [int(x) for x in blocks[j, i]]
            c0, c1 = b[0] + 256 * b[1], b[2] + 256 * b[3]
            def rgb(c):
                r, g, bl = c >> 11, (c >> 5) & 0x3F, c & 0x1F
                return [(r << 3) | (r >> 2), (g << 2) | (g >> 4), (bl << 3) | (bl >> 2)]
            p0, p1 = rgb(c0), rgb(c1)
            if c0 > c1:
                pal = [p0, p1, [(2 * a + e) // 3 for a, e in zip(p0, p1)],
                       [(a + 2 * e) // 3 for a, e in zip(p0, p1)]]
            else:
                pal = [p0, p1, [(a + e) // 2 for a, e in zip(p0, p1)], [0, 0, 0]]
            for y in range(4):
                for x in range(4):
                    out[4 * j + y, 4 * i + x] = pal[(b[4 + y] >> (2 * x)) & 3]
    return out


def _image(seed=2):
    y, x = np.mgrid[0:H, 0:W]
    rng = np.random.default_rng(seed)
    img = np.stack([128 + 100 * np.sin(0.05 * x * (c + 1) + 0.03 * y) for c in range(3)], -1)
    img += ((x // 17 + y // 13) % 5 == 0)[..., None] * 60 + rng.integers(-6, 7, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    d = tmp_path_factory.mktemp("bc1")
    img = _image()
    raw = build_pack(img, d / "raw.pack", tile_size=T, border=B, codec="raw")
    bc1 = build_pack(img, d / "bc1.pack", tile_size=T, border=B, codec="bc1")
    return raw, bc1


def _keys(pack):
    p = pack.paintings[0]
    return [(0, l, tx, ty) for l in range(p.levels)
            for ty in range(p.level_tiles[l][1]) for tx in range(p.level_tiles[l][0])]


def test_core_decoder_equals_numpy_reference_bit_for_bit(packs):
    raw, bc1 = packs
    assert bc1.codec == "bc1" and bc1.slot_format == "bc1" and raw.slot_format == "rgb8"
    assert bc1.slot_bytes * 6 == raw.slot_bytes == T * T * 3
    pure = PurePack(bc1.path)
    keys = _keys(bc1)
    for i, k in enumerate(keys):
        blocks = bc1.read_slot_tile(*k)
        assert blocks.shape == (T // 4, T // 4, 8)
        decoded = bc1.read_tile(*k)
        if i % 5 == 0:  # the slow reference on a fifth of the tiles, the rest vectorised
            np.testing.assert_array_equal(decoded, reference_bc1(blocks))
        np.testing.assert_array_equal(decoded, pure.read_tile(*k))
    pure.close()


def test_pure_reader_decoder_on_random_blocks(rng):
    blocks = rng.integers(0, 256, (6, 7, 8), dtype=np.uint8)
    blocks[0, :, 2:4] = blocks[0, :, 0:2]  # c0 == c1: the 3-colour mode
    np.testing.assert_array_equal(decode_bc1(blocks), reference_bc1(blocks))


def test_quality_is_bc1s_not_a_broken_encoders(packs):
    raw, bc1 = packs
    err = [(bc1.read_tile(*k).astype(float) - raw.read_tile(*k)) ** 2 for k in _keys(raw)]
    psnr = 10 * np.log10(255 ** 2 / np.mean(err))
    assert 25 < psnr < 60  # lossy (it is not the raw tile) but close (a noisy test image)


def test_cluster_fit_is_no_worse_than_range_fit(packs, tmp_path):
    raw, bc1 = packs
    cluster = build_pack(_image(), tmp_path / "c.pack", tile_size=T, border=B, codec="bc1",
                         bc1_fit="cluster")
    def se(p):
        return sum(float(((p.read_tile(*k).astype(float) - raw.read_tile(*k)) ** 2).sum())
                   for k in _keys(raw))
    assert se(cluster) < se(bc1)
    k = _keys(raw)[3]
    np.testing.assert_array_equal(cluster.read_tile(*k), reference_bc1(cluster.read_slot_tile(*k)))
    with pytest.raises(ValueError, match="bc1_fit"):
        build_pack(_image(), tmp_path / "x.pack", tile_size=T, border=B, codec="bc1",
                   bc1_fit="best")


def test_loader_and_cache_keep_the_blocks(packs):
    raw, bc1 = packs
    keys = _keys(bc1)
    with TileLoader(bc1, "lockfree", 2) as loader:
        loader.submit(keys)
        got = {}
        while len(got) < len(keys):
            for k, data in loader.poll():
                got[tuple(k)] = data
    for k in keys:
        np.testing.assert_array_equal(got[k], bc1.read_slot_tile(*k))
    vt = VirtualTexture(bc1, (12, 12))
    assert vt.format == "bc1" and vt.slot_bytes == T * T // 2
    assert vt.physical.shape == (144, T // 4, T // 4, 8)
    for k in keys:
        vt.insert(k, got[k])
    with pytest.raises(ValueError, match="bc1"):
        vt.insert(keys[0], raw.read_tile(*keys[0]))  # RGB into a BC1 slot: refused
    with TileLoader(raw, "lockfree", 1) as loader, pytest.raises(ValueError, match="slots"):
        vt.drain(loader)  # a raw pack's loader does not feed a bc1 cache


def test_sampling_across_seams_against_the_raw_pack(packs):
    """Across tile seams (within a texel of k P) at every level, a bc1 sample differs from the
    raw pack's by at most the largest texel error of that level: a bilinear sample is a convex
    blend of 4 texels, so |blend(decoded) - blend(raw)| <= max |decoded - raw| over them;
    mismatched borders between neighbouring tiles would break this bound at the seams."""
    raw, bc1 = packs
    vr, vb = VirtualTexture(raw, (12, 12)), VirtualTexture(bc1, (12, 12))
    for k in _keys(raw):
        vr.insert(k, raw.read_tile(*k))
        vb.insert(k, bc1.read_slot_tile(*k))
    rng = np.random.default_rng(5)
    P = T - 2 * B
    p = raw.paintings[0]
    for l in range(p.levels):
        err = max(np.abs(bc1.read_tile(*k).astype(int) - raw.read_tile(*k)).max()
                  for k in _keys(raw) if k[1] == l)
        wl, hl = p.level_sizes[l]
        n = 4000
        sx = P * rng.integers(0, max(wl // P, 1) + 1, n) + rng.uniform(-1, 1, n)
        sy = np.where(rng.random(n) < 0.5, P * rng.integers(0, max(hl // P, 1) + 1, n)
                      + rng.uniform(-1, 1, n), rng.uniform(0, hl, n))
        u, v = np.clip(sx / wl, 0, 1), np.clip(sy / hl, 0, 1)
        a, la = vb.sample(0, u, v, float(l))
        b, lb = vr.sample(0, u, v, float(l))
        assert (la == l).all() and (lb == l).all()
        assert np.abs(a - b).max() <= err + 1e-3
        # and on average no worse at the seams than anywhere else in the level
        ur, vr_ = rng.random(n), rng.random(n)
        away = np.abs(vb.sample(0, ur, vr_, float(l))[0] - vr.sample(0, ur, vr_, float(l))[0])
        assert np.abs(a - b).mean() < 1.25 * away.mean() + 0.5


def test_cli_pack_codec_bc1(tmp_path, gigascroll_cli):
    from PIL import Image
    Image.fromarray(_image(3)).save(tmp_path / "in.png")
    r = gigascroll_cli("pack", tmp_path / "in.png", "-o", tmp_path / "o.pack", "--codec", "bc1",
                       "--tile-size", "32", "--border", "4")
    assert r.returncode == 0, r.stderr
    assert TilePack(tmp_path / "o.pack").codec == "bc1"
    r = gigascroll_cli("pack", tmp_path / "in.png", "-o", tmp_path / "bad.pack", "--codec", "bc1",
                       "--tile-size", "32", "--border", "3")
    assert r.returncode == 2 and "multiples of 4" in r.stderr
    assert not (tmp_path / "bad.pack").exists()

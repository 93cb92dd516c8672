"""Streaming runtime (gigascroll.runtime) against independent references: numpy
bilinear/trilinear sampling of the source image and of whole mip levels, brute-force
fallback levels, direct pack reads."""

import shutil
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import gigascroll
from gigascroll import LoadError, MipTexture, TileLoader, VirtualTexture, build_pack, read_level

W, H, T, B = 301, 173, 32, 2  # odd sizes: edge texels, partial tiles, odd mip halving


@pytest.fixture(scope="module")
def image():
    return np.random.default_rng(7).integers(0, 256, (H, W, 3), dtype=np.uint8)


@pytest.fixture(scope="module")
def pack(tmp_path_factory, image):
    return build_pack(image, tmp_path_factory.mktemp("rt") / "p", tile_size=T, border=B)


@pytest.fixture(scope="module")
def levels(pack, image):
    # Level 0 is the source image itself; coarser levels are assembled from the tiles'
    # payloads (the pack's own tests check them against exact averages of the source).
    return [image] + [read_level(pack, 0, l) for l in range(1, pack.paintings[0].levels)]


def all_keys(pack, painting=0):
    p = pack.paintings[painting]
    return [(painting, l, tx, ty) for l, (nx, ny) in enumerate(p.level_tiles)
            for ty in range(ny) for tx in range(nx)]


def ref_bilinear(level_img, level, u, v, width, height):
    """Clamp-to-edge bilinear of one level at uv, texel centres at i + 0.5, uv scaled by the
    level-0 size / 2^level (the padded pyramid's geometry)."""
    h, w = level_img.shape[:2]
    img = level_img.astype(np.float64)

    def axis(x, n):
        x = np.clip(x, 0.5, n - 0.5) - 0.5
        i0 = np.floor(x).astype(np.int64)
        return i0, np.minimum(i0 + 1, n - 1), x - i0

    x0, x1, fx = axis(np.asarray(u, np.float64) * width / 2.0 ** level, w)
    y0, y1, fy = axis(np.asarray(v, np.float64) * height / 2.0 ** level, h)
    fx, fy = fx[..., None], fy[..., None]
    return ((1 - fx) * (1 - fy) * img[y0, x0] + fx * (1 - fy) * img[y0, x1]
            + (1 - fx) * fy * img[y1, x0] + fx * fy * img[y1, x1])


def full_vt(pack, slots=(24, 24)):
    vt = VirtualTexture(pack, slots)
    for k in all_keys(pack):
        if not vt.is_resident(k):
            assert vt.insert(k, pack.read_tile(*k)) is None
    return vt


@pytest.fixture(scope="module")
def vt_full(pack):
    return full_vt(pack)


unit = st.one_of(st.floats(0.0, 1.0), st.sampled_from([0.0, 1.0, 0.5 / W, 1 - 0.5 / W, 0.5 / H,
                                                       1 - 0.5 / H, 1e-12, 1 - 1e-12]))
uv_lists = st.lists(st.tuples(unit, unit, st.floats(0.0, 4.0)), min_size=1, max_size=64)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(samples=uv_lists)
def test_bilinear_equals_direct_sampling_of_the_level(vt_full, levels, samples):
    u, v, lod = (np.array(c) for c in zip(*samples))
    lod = np.floor(lod)
    rgb, answered = vt_full.sample(0, u, v, lod)
    assert (answered == lod).all()
    ref = np.stack([ref_bilinear(levels[int(l)], int(l), u[i], v[i], W, H)
                    for i, l in enumerate(lod)])
    np.testing.assert_allclose(rgb, ref, atol=2e-3)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(samples=uv_lists)
def test_trilinear_blends_the_two_levels(vt_full, levels, samples):
    u, v, lod = (np.array(c) for c in zip(*samples))
    rgb, answered = vt_full.sample(0, u, v, lod.astype(np.float32), filter="trilinear")
    lod32 = lod.astype(np.float32).astype(np.float64)
    l0 = np.floor(lod32).astype(int)
    ref = []
    for i in range(len(u)):
        a = ref_bilinear(levels[l0[i]], l0[i], u[i], v[i], W, H)
        f = lod32[i] - l0[i]
        if f > 0:
            a = a + f * (ref_bilinear(levels[l0[i] + 1], l0[i] + 1, u[i], v[i], W, H) - a)
        ref.append(a)
    np.testing.assert_allclose(rgb, np.stack(ref), atol=2e-3)
    assert (answered == l0).all()


def finest_resident_ancestor(vt, pack, level, u, v):
    """Brute force: walk up from `level` until a resident tile covers uv."""
    p = pack.paintings[0]
    P = pack.payload
    for a in range(level, p.levels):
        w, h = p.level_sizes[a]
        x = min(max(u * W / 2 ** a, 0.5), w - 0.5)
        y = min(max(v * H / 2 ** a, 0.5), h - 0.5)
        if vt.is_resident((0, a, int(x // P), int(y // P))):
            return a
    raise AssertionError("no resident ancestor: the coarsest tile must be pinned")


def test_missing_tiles_answer_with_the_finest_resident_ancestor(pack, levels, rng):
    vt = VirtualTexture(pack, (4, 4))  # 16 slots: most tiles cannot be resident
    keys = all_keys(pack)
    for i in rng.permutation(len(keys))[:40]:
        vt.insert(keys[i], pack.read_tile(*keys[i]))
    assert vt.stats()["evictions"] > 0
    assert vt.page_table_matches_rebuild()
    n = 3000
    u, v = rng.random(n), rng.random(n)
    lod = rng.integers(0, pack.paintings[0].levels, n).astype(np.float32)
    rgb, answered = vt.sample(0, u, v, lod)
    expect = [finest_resident_ancestor(vt, pack, int(lod[i]), u[i], v[i]) for i in range(n)]
    np.testing.assert_array_equal(answered, expect)
    assert (answered > lod).any()
    ref = np.stack([ref_bilinear(levels[a], a, u[i], v[i], W, H) for i, a in enumerate(answered)])
    np.testing.assert_allclose(rgb, ref, atol=2e-3)


def test_far_end_of_a_196301_texel_painting_is_exact_to_a_256th_texel(tmp_path):
    # VT-mobile-VR Table 4's widest painting, 64 rows high to keep the pack small. Columns
    # alternate 0 / 255, so a bilinear sample between two texels reads its fraction directly.
    Wf, Hf = 196301, 64
    img = np.zeros((Hf, Wf, 3), np.uint8)
    img[:, 1::2] = 255
    pack = build_pack(img, tmp_path / "wide", tile_size=32, border=2)
    vt = VirtualTexture(pack, (48, 48))
    P = pack.payload
    for tx in ((Wf - 3) // P, (Wf - 2) // P):
        vt.insert((0, 0, tx, 1), pack.read_tile(0, 0, tx, 1))
    k = np.arange(257)
    x0 = (Wf - 3) + 0.5 + k / 256.0
    u = x0 / Wf
    v = np.full_like(u, 40.5 / Hf)
    expect = 255.0 * np.where((Wf - 3) % 2, 1 - k / 256.0, k / 256.0)
    rgb, answered = vt.sample(0, u, v)
    assert (answered == 0).all()
    assert np.abs(rgb[:, 0] - expect).max() < 0.1  # 1/256 texel is 1 unit here
    # The same uv rounded to float32 misses by several units: the test can tell.
    rgb32, _ = vt.sample(0, u.astype(np.float32), v)
    assert np.abs(rgb32[:, 0] - expect).max() > 1.0


def test_cache_stats_lru_and_pinning(pack):
    vt = VirtualTexture(pack, (3, 3))
    s = vt.stats()
    assert s["slots"] == 9 and s["pinned"] >= 1 and s["resident"] == s["pinned"]
    coarsest = (0, pack.paintings[0].levels - 1, 0, 0)
    assert vt.is_pinned(coarsest)
    keys = [(0, 0, i, 0) for i in range(9)]
    free = 9 - s["pinned"]
    for k in keys[:free]:
        assert vt.insert(k, pack.read_tile(*k)) is None
    assert vt.request([keys[0], keys[free]]) == [keys[free]]  # keys[0] is now most recent
    evicted = vt.insert(keys[free], pack.read_tile(*keys[free]))
    assert evicted == (keys[1] if free > 1 else keys[0])
    s = vt.stats()
    assert (s["hits"], s["misses"], s["evictions"]) == (1, 1, 1)
    assert vt.is_pinned(coarsest) and vt.page_table_matches_rebuild()
    level, slot = vt.lookup(keys[0])
    assert level == 0 and 0 <= slot < 9


def test_physical_texture_holds_each_resident_tile_in_its_slot(pack, vt_full):
    """The physical view is tile-major: slot s is the tile the page table points at."""
    phys = vt_full.physical
    assert phys.shape == (24 * 24, T, T, 3) and phys.dtype == np.uint8
    assert not phys.flags.writeable
    for k in all_keys(pack)[::7]:
        level, slot = vt_full.lookup(k)
        assert level == k[1]
        np.testing.assert_array_equal(phys[slot], pack.read_tile(*k).reshape(T, T, 3))


def test_plain_mip_texture_matches_the_full_vt(pack, vt_full, rng):
    mip = MipTexture(pack)
    u, v = rng.random((40, 50)), rng.random((40, 50))
    lod = rng.random((40, 50)) * (mip.levels - 1)
    for f in ("bilinear", "trilinear"):
        a, la = vt_full.sample(0, u, v, lod, filter=f)
        b, lb = mip.sample(u, v, lod, filter=f)
        assert a.shape == (40, 50, 3) and la.shape == (40, 50)
        np.testing.assert_allclose(a, b, atol=1e-3)
        np.testing.assert_array_equal(la, lb)


@pytest.mark.parametrize("mode,threads", [("lockfree", 1), ("lockfree", 2), ("locked", 1), ("locked", 3)])
def test_loader_delivers_every_tile_once_with_the_pack_bytes(pack, mode, threads):
    keys = all_keys(pack) * 3
    got = []
    with TileLoader(pack, mode, threads, queue_capacity=16, pool_tiles=4) as loader:
        loader.submit(np.array(keys))
        deadline = time.monotonic() + 60
        while len(got) < len(keys) and time.monotonic() < deadline:
            batch = loader.poll(max_tiles=7)
            assert len(batch) <= 7
            got += batch
            if not batch:
                time.sleep(0.001)
        assert loader.stats()["loaded"] == len(keys)
    assert loader.closed
    assert sorted(k for k, _ in got) == sorted(keys)
    for k, data in got:
        np.testing.assert_array_equal(data, pack.read_tile(*k))


def test_loader_reports_a_corrupt_tile_and_keeps_going(pack, tmp_path):
    bad = tmp_path / "bad"
    shutil.copytree(pack.path, bad)
    copy = gigascroll.TilePack(bad)
    offset, length, _ = copy.locate(0, 0, 2, 1)
    with open(bad / "tiles-00000.bin", "r+b") as f:
        f.seek(offset + length // 2)
        byte = f.read(1)
        f.seek(offset + length // 2)
        f.write(bytes([byte[0] ^ 0xFF]))
    with TileLoader(copy, "lockfree", 1) as loader:
        loader.submit([(0, 0, 2, 1), (0, 0, 0, 0)])
        results = []
        deadline = time.monotonic() + 60
        while len(results) < 2 and time.monotonic() < deadline:
            results += loader.poll()
        res = dict(results)
        assert isinstance(res[(0, 0, 2, 1)], LoadError)
        assert "checksum" in str(res[(0, 0, 2, 1)])
        assert isinstance(res[(0, 0, 0, 0)], np.ndarray)
        vt = VirtualTexture(copy, (4, 4))
        loader.submit([(0, 1, 0, 0), (0, 0, 2, 1)])
        arrived, failed = [], []
        deadline = time.monotonic() + 60
        while len(arrived) < 2 and time.monotonic() < deadline:
            a, f = vt.drain(loader)
            arrived, failed = arrived + a.tolist(), failed + f
        inserted = len(arrived) - len(failed)
        assert sorted(arrived) == sorted(gigascroll.pack_request(*k) for k in [(0, 1, 0, 0), (0, 0, 2, 1)])
        assert inserted == 1 and vt.is_resident((0, 1, 0, 0))
        assert failed[0][0] == (0, 0, 2, 1) and "checksum" in failed[0][1]


def test_loader_close_with_work_in_flight(pack):
    loader = TileLoader(pack, "lockfree", 2, queue_capacity=64, pool_tiles=4)
    loader.submit(np.array(all_keys(pack) * 40))
    loader.close()  # must return promptly, dropping queued commands
    rest = loader.poll()
    s = loader.stats()
    assert s["loaded"] + s["failed"] == len(rest)
    assert s["loaded"] + s["failed"] + s["cancelled"] == s["submitted"]
    with pytest.raises(ValueError, match="closed"):
        loader.submit([(0, 0, 0, 0)])


def test_bad_input_raises_clear_errors(pack, vt_full):
    with pytest.raises(ValueError, match="mode"):
        TileLoader(pack, "fast")
    with pytest.raises(ValueError, match="threads"):
        TileLoader(pack, "locked", 0)
    with TileLoader(pack) as loader:
        with pytest.raises(ValueError, match="not in the pack"):
            loader.submit([(0, 0, 99, 0)])
        with pytest.raises(ValueError, match="shape"):
            loader.submit([(0, 0, 0)])
        with pytest.raises(ValueError, match="integers"):
            loader.submit(np.zeros((2, 4), np.float32))
        with pytest.raises(ValueError):
            loader.submit([(0, 0, -1, 0)])
        with pytest.raises(ValueError):
            loader.poll(-1)
    with pytest.raises(ValueError, match="pinned"):
        VirtualTexture(pack, (1, 1))
    with pytest.raises(ValueError, match="NaN"):
        vt_full.sample(0, np.array([np.nan]), np.array([0.5]))
    with pytest.raises(ValueError, match="NaN"):
        vt_full.sample(0, np.array([0.5]), np.array([0.5]), lod=np.array([np.nan]))
    with pytest.raises(ValueError, match="same shape"):
        vt_full.sample(0, np.zeros(3), np.zeros(4))
    with pytest.raises(ValueError, match="filter"):
        vt_full.sample(0, np.zeros(3), np.zeros(3), filter="cubic")
    with pytest.raises(ValueError, match="painting"):
        vt_full.sample(5, np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="must be a"):
        vt_full.insert((0, 0, 0, 0), np.zeros((T, T, 4), np.uint8))
    with pytest.raises(ValueError, match="uint8"):
        vt_full.insert((0, 0, 0, 0), np.zeros((T, T, 3), np.float32))
    with pytest.raises(ValueError, match="out of range"):
        vt_full.insert((0, 0, 50, 0), np.zeros((T, T, 3), np.uint8))
    # Out-of-range uv clamp to the edge instead of failing.
    a, _ = vt_full.sample(0, np.array([-3.0, 7.0]), np.array([0.0, 1.0]))
    b, _ = vt_full.sample(0, np.array([0.0, 1.0]), np.array([0.0, 1.0]))
    np.testing.assert_array_equal(a, b)


def test_empty_and_single_key_batches_are_accepted(pack):
    # numpy gives empty and one-row arrays arbitrary strides: they must not be rejected.
    vt = VirtualTexture(pack, slots=(8, 8))
    key = all_keys(pack)[0]
    with TileLoader(pack, "lockfree", 1) as loader:
        loader.submit([])
        loader.submit(np.zeros((0, 4), np.int64))
        assert vt.request([]) == []
        loader.submit([key])
        deadline = time.monotonic() + 30
        got = []
        while not got and time.monotonic() < deadline:
            got = loader.poll()
            time.sleep(0.001)
    assert [k for k, _ in got] == [tuple(key)]


def test_request_keys_in_and_out(pack):
    # A 1-D uint64 array of request keys (views' pack_request layout) is the same set of
    # tiles as the (n, 4) form: the same misses, loads and drained arrivals.
    keys = all_keys(pack)[:12]
    requests = np.array([gigascroll.pack_request(*k) for k in keys], np.uint64)
    a, b = VirtualTexture(pack, (8, 8)), VirtualTexture(pack, (8, 8))
    missing = a.request(requests)
    assert missing.dtype == np.uint64 and missing.ndim == 1
    assert [gigascroll.pack_request(*k) for k in b.request(keys)] == missing.tolist()
    assert a.stats() == b.stats()
    with TileLoader(pack, "lockfree", 1) as loader:
        loader.submit(missing)
        arrived, failed = np.zeros(0, np.uint64), []
        deadline = time.monotonic() + 30
        while arrived.size < missing.size and time.monotonic() < deadline:
            got, f = a.drain(loader)
            arrived, failed = np.concatenate([arrived, got]), failed + f
    assert failed == [] and sorted(arrived.tolist()) == sorted(missing.tolist())
    assert a.request(requests).size == 0  # all resident now
    with TileLoader(pack) as loader:
        with pytest.raises(ValueError):
            loader.submit(np.array([gigascroll.pack_request(0, 0, 99, 0)], np.uint64))


def test_strided_inputs_read_as_their_contiguous_copies(pack, vt_full, rng):
    # The wrappers leave contiguity to the core: strided uv, lod and keys give what their
    # contiguous copies give.
    u, v, lod = rng.random(40), rng.random(40), rng.random(40).astype(np.float32) * 3
    strided = (u[::2], v[::2], lod[::2])
    assert not strided[0].flags.c_contiguous
    a, la = vt_full.sample(0, *strided, filter="trilinear")
    b, lb = vt_full.sample(0, *(np.ascontiguousarray(x) for x in strided), filter="trilinear")
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(la, lb)
    keys = np.array([gigascroll.pack_request(*k) for k in all_keys(pack)], np.uint64)
    x, y = VirtualTexture(pack, (8, 8)), VirtualTexture(pack, (8, 8))
    assert x.request(keys[::3]).tolist() == y.request(np.ascontiguousarray(keys[::3])).tolist()
    rows = np.array(all_keys(pack), np.int64)[::2]
    fortran = np.asfortranarray(rows)
    assert not fortran.flags.c_contiguous
    assert x.request(fortran) == y.request(rows)


def test_loader_sizes_are_bounded_before_allocation(small_pack):
    # Huge queue or pool sizes are refused with the memory they would need, not allocated.
    pack = gigascroll.TilePack(small_pack[0])
    for kwargs, what in (({"queue_capacity": 2 ** 61}, "queue_capacity"),
                         ({"pool_tiles": 2 ** 40}, "pool_tiles")):
        with pytest.raises(ValueError, match=what) as e:
            TileLoader(pack, **kwargs)
        assert "MiB" in str(e.value)

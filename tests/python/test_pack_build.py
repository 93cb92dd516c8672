"""Building tile packs (gigascroll.pack.build): every tile against an independent numpy
reference, codecs, the merged page-table layout, and builds that fail or are interrupted."""

import json
import subprocess
import sys

import numpy as np
import pytest
from pack_reference import check_pack_against, noise, write_image

import gigascroll
from gigascroll import build_pack, painting_geometry
from gigascroll.pack import ArraySource


@pytest.mark.parametrize("h,w", [(1, 1), (37, 1000), (1000, 37), (129, 257)])
@pytest.mark.parametrize("tile,border", [(16, 2), (8, 0)])
def test_tiles_match_reference(tmp_path, h, w, tile, border):
    img = noise(h, w, seed=h * 7 + w)
    pack = build_pack(img, tmp_path / "p", tile_size=tile, border=border)
    assert pack.tile_size == tile and pack.border == border and pack.payload == tile - 2 * border
    check_pack_against(pack, 0, img)


def test_default_tile_size_and_odd_image(tmp_path):
    img = noise(301, 517, seed=5)
    pack = build_pack(img, tmp_path / "p")
    assert (pack.tile_size, pack.border, pack.codec) == (128, 4, "raw")
    check_pack_against(pack, 0, img)


def test_banding_does_not_change_the_result(tmp_path):
    img = noise(203, 151, seed=9)
    a = build_pack(img, tmp_path / "a", tile_size=16, border=3, band_rows=1)
    b = build_pack(img, tmp_path / "b", tile_size=16, border=3, band_rows=1000, threads=1)
    assert a.tile_count == b.tile_count
    # Tiles land in tiles.bin in a banding-dependent order; their contents must not change.
    for level, (nx, ny) in enumerate(a.paintings[0].level_tiles):
        for ty in range(ny):
            for tx in range(nx):
                assert a.locate(0, level, tx, ty)[2] == b.locate(0, level, tx, ty)[2]
                assert np.array_equal(a.read_tile(0, level, tx, ty), b.read_tile(0, level, tx, ty))


def test_constant_image_has_no_bleeding_at_edges(tmp_path):
    # With clamping and exact averages, a constant image stays constant in every texel of
    # every tile, borders and odd edges included (padding would pull edges toward 0).
    img = np.full((67, 131, 3), (200, 10, 99), np.uint8)
    pack = build_pack(img, tmp_path / "p", tile_size=16, border=4)
    for level, (nx, ny) in enumerate(pack.paintings[0].level_tiles):
        for ty in range(ny):
            for tx in range(nx):
                t = pack.read_tile(0, level, tx, ty)
                assert (t == np.array([200, 10, 99], np.uint8)).all()


def test_geometry_function_matches_pack(tmp_path):
    g = painting_geometry(152089, 6083, 128, 4)
    assert g["table_size"] == (2048, 64)
    assert g["levels"][0]["tiles"] == (1268, 51)
    assert g["uv_scale"] == pytest.approx((152089 / (2048 * 120), 6083 / (64 * 120)))
    assert len(g["levels"]) == 12  # 152089 / 2^11 = 75 <= 120, 2^10 -> 149 > 120
    with pytest.raises(ValueError):
        painting_geometry(0, 10, 128, 4)
    with pytest.raises(ValueError):
        painting_geometry(10, 10, 8, 4)


def test_zstd_round_trip_equals_raw(tmp_path):
    img = noise(150, 260, seed=3)
    img[:, :100] = 128  # compressible part
    raw = build_pack(img, tmp_path / "raw", tile_size=32, border=4, codec="raw")
    z = build_pack(img, tmp_path / "z", tile_size=32, border=4, codec="zstd")
    assert z.codec == "zstd"
    for level, (nx, ny) in enumerate(raw.paintings[0].level_tiles):
        for ty in range(ny):
            for tx in range(nx):
                assert np.array_equal(raw.read_tile(0, level, tx, ty), z.read_tile(0, level, tx, ty))
    assert (tmp_path / "z" / "tiles-00000.bin").stat().st_size < (tmp_path / "raw" / "tiles-00000.bin").stat().st_size
    check_pack_against(z, 0, img)


def test_random_geometries_match_reference(tmp_path_factory):
    """Property test: any small image size, tile size and border, any band size."""
    from hypothesis import given, settings, HealthCheck, strategies as st

    @settings(max_examples=15, deadline=None, suppress_health_check=list(HealthCheck))
    @given(h=st.integers(1, 70), w=st.integers(1, 70), border=st.integers(0, 3),
           extra=st.integers(1, 9), band=st.integers(1, 40), seed=st.integers(0, 1000))
    def check(h, w, border, extra, band, seed):
        img = noise(h, w, seed=seed)
        out = tmp_path_factory.mktemp("h") / "p"
        pack = build_pack(img, out, tile_size=max(2, 2 * border + extra), border=border,
                          band_rows=band)
        check_pack_against(pack, 0, img)

    check()


# ----------------------------------------------------------------------------- layouts


def test_multi_painting_layout_aligned_and_disjoint_at_every_level(tmp_path):
    sizes = [(37, 1000), (129, 257), (1, 1), (300, 64), (64, 300), (17, 513)]
    imgs = [noise(h, w, seed=i) for i, (h, w) in enumerate(sizes)]
    pack = build_pack(imgs, tmp_path / "p", tile_size=16, border=2, names=[f"n{i}" for i in range(6)])
    Mc, Nc = pack.table_size
    assert Mc & (Mc - 1) == 0 and Nc & (Nc - 1) == 0
    ps = pack.paintings
    assert [p.name for p in ps] == [f"n{i}" for i in range(6)]
    max_level = max(p.table_size[0].bit_length() for p in ps)
    for level in range(max_level):
        grid = np.zeros((max(1, Nc >> level), max(1, Mc >> level)), np.int32)
        for p in ps:
            (Mp, Np), (x, y) = p.table_size, p.table_offset
            assert x % Mp == 0 and y % Np == 0
            assert x + Mp <= Mc and y + Np <= Nc
            if (1 << level) > min(Mp, Np):
                continue  # thinner than one entry: the runtime pins these tail tiles
            # eqs (5, 6): the region at level l is (Mp >> l) x (Np >> l) at (x >> l, y >> l)
            assert (x >> level) << level == x and (y >> level) << level == y
            grid[y >> level:(y >> level) + (Np >> level), x >> level:(x >> level) + (Mp >> level)] += 1
        assert grid.max() <= 1
    for i, img in enumerate(imgs):
        check_pack_against(pack, i, img)
    manifest = json.loads((tmp_path / "p" / "manifest.json").read_text())
    pt = manifest["page_table"]
    assert pt["packer"] == "brkga"
    assert 0 < pt["shelf_fill_ratio"] <= pt["brkga_fill_ratio"] <= 1
    area = sum(p.table_size[0] * p.table_size[1] for p in ps)
    assert pt["fill_ratio"] == pytest.approx(area / (Mc * Nc))


def brute_force_check(sizes, w, h, offsets):
    grid = np.zeros((h, w), np.int32)
    for (mw, mh), (x, y) in zip(sizes, offsets):
        assert x % mw == 0 and y % mh == 0
        grid[y:y + mh, x:x + mw] += 1
    assert grid.max() <= 1
    return grid.sum() / grid.size


@pytest.mark.parametrize("seed", range(6))
def test_layout_packers_are_valid_and_brkga_not_worse(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 25))
    sizes = [(int(2 ** rng.integers(0, 6)), int(2 ** rng.integers(0, 6))) for _ in range(n)]
    shelf = gigascroll.plan_layout(sizes, "shelf", seed)
    brkga = gigascroll.plan_layout(sizes, "brkga", seed)
    f_shelf = brute_force_check(sizes, *shelf[:3])
    f_brkga = brute_force_check(sizes, *brkga[:3])
    assert shelf[3]["fill_ratio"] == pytest.approx(f_shelf)
    assert brkga[3]["fill_ratio"] == pytest.approx(f_brkga)
    assert f_brkga >= f_shelf
    assert gigascroll.plan_layout(sizes, "brkga", seed)[:3] == brkga[:3]  # deterministic
    with pytest.raises(ValueError):
        gigascroll.plan_layout([(3, 4)])
    with pytest.raises(ValueError):
        gigascroll.plan_layout(sizes, "tetris")


# ----------------------------------------------------------------------------- bad input


def test_bad_build_arguments(tmp_path):
    img = noise(10, 10)
    with pytest.raises(ValueError, match="border"):
        build_pack(img, tmp_path / "a", tile_size=8, border=4)
    with pytest.raises(ValueError, match="codec"):
        build_pack(img, tmp_path / "a", codec="jpeg")
    with pytest.raises(ValueError, match="empty"):
        build_pack(np.zeros((0, 5, 3), np.uint8), tmp_path / "a")
    with pytest.raises(ValueError):
        build_pack([], tmp_path / "a")
    with pytest.raises(OSError, match="no such"):
        build_pack(tmp_path / "missing.png", tmp_path / "a")
    with pytest.raises(ValueError, match="NaN"):
        build_pack(np.full((4, 4, 3), np.nan, np.float32), tmp_path / "a")
    assert not any(tmp_path.iterdir())  # nothing left behind


def test_existing_output_needs_force(tmp_path):
    img = noise(20, 30)
    build_pack(img, tmp_path / "p", tile_size=16, border=2)
    with pytest.raises(OSError, match="already exists"):
        build_pack(img, tmp_path / "p")
    pack = build_pack(img[:, :, ::-1], tmp_path / "p", tile_size=16, border=2, force=True)
    check_pack_against(pack, 0, img[:, :, ::-1])
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("keep me")
    with pytest.raises(OSError, match="not a tile pack"):
        build_pack(img, tmp_path / "other", force=True)
    assert (tmp_path / "other" / "notes.txt").exists()
    # A source tree that happens to hold a manifest.json is not a pack either: --force keeps it.
    src = tmp_path / "src"
    src.mkdir()
    (src / "manifest.json").write_text('{"name": "my-web-app"}')
    (src / "main.py").write_text("print('hi')")
    with pytest.raises(OSError, match="not a tile pack"):
        build_pack(img, src, force=True)
    assert (src / "main.py").exists() and (src / "manifest.json").exists()
    (src / "main.py").unlink()  # only a manifest, but not a pack's
    with pytest.raises(OSError, match="not a tile pack"):
        build_pack(img, src, force=True)


@pytest.mark.parametrize("name,content", [("garbage.png", b"\x89PNG\r\n\x1a\nnot really"),
                                          ("empty.tif", b""), ("text.jpg", b"hello")])
def test_unreadable_image(tmp_path, name, content):
    (tmp_path / name).write_bytes(content)
    with pytest.raises(OSError):
        build_pack(tmp_path / name, tmp_path / "p")
    assert not (tmp_path / "p").exists()
    assert [f.name for f in tmp_path.iterdir()] == [name]


def test_truncated_image_fails_without_output(tmp_path):
    pix = noise(400, 300, seed=2)
    path = tmp_path / "t.tif"
    write_image(path, pix)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(OSError):
        build_pack(path, tmp_path / "p", tile_size=16, border=2)
    assert sorted(f.name for f in tmp_path.iterdir()) == ["t.tif"]


def test_interrupted_build_leaves_nothing_that_opens(tmp_path):
    class Interrupting(ArraySource):
        def bands(self):
            it = super().bands()
            yield next(it)
            raise KeyboardInterrupt

    src = Interrupting(noise(300, 40), "x", band_rows=50)
    with pytest.raises(KeyboardInterrupt):
        build_pack([src], tmp_path / "p", tile_size=16, border=2)
    assert not any(tmp_path.iterdir())


def test_disk_full_mid_build(tmp_path):
    # A file-size limit makes write() fail with EFBIG mid-build, like a full disk.
    code = f"""
import resource, signal, numpy as np, gigascroll
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20))
img = np.random.default_rng(0).integers(0, 256, (600, 700, 3), dtype=np.uint8)
try:
    gigascroll.build_pack(img, {str(tmp_path / 'p')!r}, tile_size=32, border=2)
except OSError as e:
    print('OSError', e)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("OSError") and "write failed" in r.stdout
    assert not any(tmp_path.iterdir())

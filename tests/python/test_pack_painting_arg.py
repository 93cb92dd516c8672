"""TilePack's per-tile methods take a painting as the object in `pack.paintings` or as its index
(the README passes `p = pack.paintings[0]`). The reference for the object form is the index form
and the pure-Python reader, which reads the same tile files independently of the core."""

import numpy as np
import pytest

import gigascroll
from gigascroll.pack.reader import PurePack


@pytest.fixture(scope="module")
def two_paintings(tmp_path_factory):
    rng = np.random.default_rng(7)
    images = [rng.integers(0, 256, (300, 500, 3), np.uint8), rng.integers(0, 256, (90, 130, 3), np.uint8)]
    path = tmp_path_factory.mktemp("arg") / "two.pack"
    return gigascroll.build_pack(images, path), path


def test_painting_object_and_index_agree(two_paintings):
    pack, path = two_paintings
    pure = PurePack(path)
    out = np.empty((pack.tile_size, pack.tile_size, 3), np.uint8)
    for i, p in enumerate(pack.paintings):
        for level, (nx, ny) in enumerate(p.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    assert pack.has_tile(p, level, tx, ty) and pack.has_tile(i, level, tx, ty)
                    tile = pack.read_tile(p, level, tx, ty)
                    np.testing.assert_array_equal(tile, pure.read_tile(i, level, tx, ty))
                    pack.read_tile_into(p, level, tx, ty, out)
                    np.testing.assert_array_equal(out, tile)
                    np.testing.assert_array_equal(pack.read_slot_tile(p, level, tx, ty), tile)
                    assert pack.locate(p, level, tx, ty) == pack.locate(i, level, tx, ty)
                    assert pack.tile_file(p, level, tx, ty) == pure.tile_file(i, level, tx, ty)
        nx = p.level_tiles[0][0]
        if nx < p.table_size[0]:  # a padding tile of the page table: no tile, either form
            assert not pack.has_tile(p, 0, nx, 0) and not pack.has_tile(i, 0, nx, 0)
    pure.close()


def test_painting_of_another_pack_is_refused(two_paintings):
    pack, path = two_paintings
    other = gigascroll.TilePack(path)  # the same files, but another pack object
    with pytest.raises(ValueError, match="not one of this pack's paintings"):
        pack.read_tile(other.paintings[0], 0, 0, 0)
    with pytest.raises(ValueError, match="not one of this pack's paintings"):
        pack.has_tile(other.paintings[1], 0, 0, 0)


def test_painting_keeps_its_pack_alive(two_paintings):
    _, path = two_paintings
    pack = gigascroll.TilePack(path)
    p = pack.paintings[1]
    expected = pack.read_tile(1, 0, 0, 0)
    np.testing.assert_array_equal(pack.read_tile(p, 0, 0, 0), expected)
    assert p.name == pack.paintings[1].name and p.width == 130


def test_other_arguments_are_still_type_checked(two_paintings):
    pack, _ = two_paintings
    with pytest.raises(TypeError):
        pack.read_tile("painting0", 0, 0, 0)
    with pytest.raises(TypeError):
        pack.has_tile(None, 0, 0, 0)


def test_pure_reader_takes_a_painting_or_its_index(two_paintings):
    pack, path = two_paintings
    pure, other = PurePack(path), PurePack(path)
    for i, p in enumerate(pure.paintings):
        np.testing.assert_array_equal(pure.read_tile(p, 0, 0, 0), pack.read_tile(i, 0, 0, 0))
        assert pure.locate(p, 0, 0, 0) == pure.locate(i, 0, 0, 0) == pack.locate(i, 0, 0, 0)
        assert pure.tile_file(p, 0, 0, 0) == pack.tile_file(i, 0, 0, 0)
    # Equal fields are not enough: the painting must be this pack's own object.
    assert other.paintings[0] == pure.paintings[0]
    with pytest.raises(ValueError, match="not one of this pack's paintings"):
        pure.read_tile(other.paintings[0], 0, 0, 0)
    pure.close()
    other.close()

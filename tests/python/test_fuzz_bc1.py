"""Hostile bc1 packs: corrupted block bytes, index entries whose length is not a BC1 tile's,
and manifests whose tile geometry blocks cannot cover. Every case is a clean OSError from
both readers (and an error result from the loader), never a crash or garbage texels."""

import json
import shutil
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from gigascroll import build_pack
from gigascroll.pack import TilePack
from gigascroll.pack.reader import PurePack
from gigascroll.runtime import LoadError, TileLoader

T = 16
ENTRY = struct.Struct("<QIIQ")


@pytest.fixture(scope="module")
def bc1_pack(tmp_path_factory):
    img = np.random.default_rng(1).integers(0, 256, (40, 52, 3), dtype=np.uint8)
    path = tmp_path_factory.mktemp("fuzzbc1") / "p"
    build_pack(img, path, tile_size=T, border=2, codec="bc1")
    return path


def _copy(src, tmp_path_factory):
    dst = tmp_path_factory.mktemp("case") / "p"
    shutil.copytree(src, dst)
    return dst


def _first_entry(path):
    raw = (path / "index.bin").read_bytes()
    return ENTRY.unpack_from(raw, 32)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pos=st.integers(0, T * T // 2 - 1), flip=st.integers(1, 255))
def test_corrupt_block_bytes_fail_the_checksum(bc1_pack, tmp_path_factory, pos, flip):
    path = _copy(bc1_pack, tmp_path_factory)
    offset, length, _ = TilePack(path).locate(0, 0, 0, 0)
    assert length == T * T // 2
    with open(path / TilePack(path).tile_file(0, 0, 0, 0), "r+b") as f:
        f.seek(offset + pos)
        b = f.read(1)[0]
        f.seek(offset + pos)
        f.write(bytes([b ^ flip]))
    pack = TilePack(path)
    for read in (pack.read_tile, pack.read_slot_tile):
        with pytest.raises(OSError, match="checksum"):
            read(0, 0, 0, 0)
    with TileLoader(pack, "lockfree", 1) as loader:
        loader.submit([(0, 0, 0, 0)])
        got = []
        while not got:
            got = loader.poll()
        assert isinstance(got[0][1], LoadError) and "checksum" in str(got[0][1])
    with PurePack(path) as pure, pytest.raises(OSError, match="checksum"):
        pure.read_tile(0, 0, 0, 0)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(length=st.integers(0, 4 * T * T).filter(lambda n: n != T * T // 2))
def test_wrong_tile_length_fails_the_size_check(bc1_pack, tmp_path_factory, length):
    path = _copy(bc1_pack, tmp_path_factory)
    raw = bytearray((path / "index.bin").read_bytes())
    offset, _, flags, checksum = ENTRY.unpack_from(raw, 32)
    ENTRY.pack_into(raw, 32, offset, length, flags, checksum)
    (path / "index.bin").write_bytes(bytes(raw))
    pack = TilePack(path)
    for read in (pack.read_tile, pack.read_slot_tile):
        with pytest.raises(OSError, match="length|outside"):
            read(0, 0, 0, 0)
    with PurePack(path) as pure, pytest.raises(OSError, match="length|outside"):
        pure.read_tile(0, 0, 0, 0)


@pytest.mark.parametrize("tile_size,border", [(18, 1), (16, 1), (14, 1)])
def test_manifest_whose_tiles_blocks_cannot_cover_is_refused(bc1_pack, tmp_path_factory,
                                                            tile_size, border):
    path = _copy(bc1_pack, tmp_path_factory)
    m = json.loads((path / "manifest.json").read_text())
    m["tile_size"], m["border"], m["payload"] = tile_size, border, tile_size - 2 * border
    (path / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(OSError):
        TilePack(path)
    with pytest.raises(OSError):
        PurePack(path)

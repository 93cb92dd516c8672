"""Reading tile packs (gigascroll.TilePack, the core's reader): damaged files are refused
with clear errors, reads check ranges and checksums, and threads may read at once."""

import json
import os

import numpy as np
import pytest

import gigascroll
from gigascroll import TilePack


def test_reader_missing_manifest(small_pack):
    path, _ = small_pack
    (path / "manifest.json").unlink()
    with pytest.raises(OSError, match="missing manifest"):
        TilePack(path)
    with pytest.raises(OSError, match="missing manifest"):
        TilePack(path.parent / "nowhere")


@pytest.mark.parametrize("which", ["tiles-00000.bin", "index.bin"])
def test_reader_wrong_magic_version_truncation(small_pack, which):
    path, _ = small_pack
    f = path / which
    data = bytearray(f.read_bytes())
    bad = bytearray(data)
    bad[0:8] = b"NOTAPACK"
    f.write_bytes(bad)
    with pytest.raises(OSError, match="magic"):
        TilePack(path)
    bad = bytearray(data)
    bad[8] = 99  # version field
    f.write_bytes(bad)
    with pytest.raises(OSError, match="version"):
        TilePack(path)
    f.write_bytes(data[:-5])
    with pytest.raises(OSError, match="truncated"):
        TilePack(path)
    f.write_bytes(data)
    TilePack(path)


def test_reader_manifest_version_and_corruption(small_pack):
    path, _ = small_pack
    m = json.loads((path / "manifest.json").read_text())
    m["version"] = 7
    (path / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(OSError, match="version"):
        TilePack(path)
    (path / "manifest.json").write_text("{ not json")
    with pytest.raises(OSError, match="manifest"):
        TilePack(path)
    m["version"] = 1
    m["paintings"][0]["width"] += 1000  # geometry no longer matches the index
    (path / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(OSError):
        TilePack(path)


def test_reader_checksum_mismatch_and_ranges(small_pack):
    path, img = small_pack
    pack = TilePack(path)
    offset, length, checksum = pack.locate(0, 0, 1, 1)
    assert length == 16 * 16 * 3
    data = bytearray((path / "tiles-00000.bin").read_bytes())
    data[offset + 100] ^= 0xFF
    (path / "tiles-00000.bin").write_bytes(data)
    pack = TilePack(path)
    with pytest.raises(OSError, match="checksum"):
        pack.read_tile(0, 0, 1, 1)
    pack.read_tile(0, 0, 0, 1)  # the others still read
    with pytest.raises(OSError, match="checksum"):
        gigascroll.verify_pack(pack)
    with pytest.raises(ValueError, match="painting"):
        pack.read_tile(1, 0, 0, 0)
    with pytest.raises(ValueError, match="level"):
        pack.read_tile(0, 99, 0, 0)
    with pytest.raises(ValueError, match="outside"):
        pack.read_tile(0, 0, 999, 0)
    Mp, Np = pack.paintings[0].table_size
    nx, ny = pack.paintings[0].level_tiles[0]
    assert nx < Mp  # 70 px / 12 = 6 tiles in an 8-wide table: padding tiles exist
    assert not pack.has_tile(0, 0, nx, 0)
    with pytest.raises(ValueError, match="not stored"):
        pack.read_tile(0, 0, nx, 0)
    with pytest.raises(ValueError, match="not stored"):
        pack.locate(0, 0, nx, 0)
    with pytest.raises(ValueError, match="shape"):
        pack.read_tile_into(0, 0, 0, 0, np.zeros((8, 8, 3), np.uint8))
    with pytest.raises(TypeError):
        pack.read_tile_into(0, 0, 0, 0, np.zeros((16, 16, 3), np.float32))


def test_concurrent_reads_agree(small_pack):
    from concurrent.futures import ThreadPoolExecutor
    path, img = small_pack
    pack = TilePack(path)
    keys = [(0, l, tx, ty) for l, (nx, ny) in enumerate(pack.paintings[0].level_tiles)
            for ty in range(ny) for tx in range(nx)] * 20
    with ThreadPoolExecutor(4) as ex:
        tiles = list(ex.map(lambda k: pack.read_tile(*k), keys))
    for k, t in zip(keys, tiles):
        assert np.array_equal(t, pack.read_tile(*k))


@pytest.mark.parametrize("name", ["manifest.json", "tiles-00000.bin", "index.bin"])
def test_a_fifo_in_a_pack_files_place_is_refused_not_waited_on(small_pack, name):
    # open() of a FIFO blocks until a writer comes: both readers refuse it after a stat.
    from gigascroll.pack.reader import PurePack
    path, _ = small_pack
    (path / name).unlink()
    os.mkfifo(path / name)
    with pytest.raises(OSError, match="not a regular file"):
        TilePack(path)
    with pytest.raises(OSError, match="not a regular file"):
        PurePack(path)
    (path / name).unlink()
    (path / name).mkdir()
    with pytest.raises(OSError, match="not a regular file"):
        TilePack(path)

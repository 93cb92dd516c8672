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


# ----------------------------------------------------------------------------- format v2

def _entries(path):
    from gigascroll.pack.reader import _ENTRY
    raw = bytearray((path / "index.bin").read_bytes())
    return raw, np.frombuffer(raw, _ENTRY, offset=32)


def make_v1_pack(v2, out):
    """The same pack in format version 1 (one tiles.bin, unseeded checksums, u32 flags), made
    here independently of the builder."""
    import shutil
    import xxhash
    shutil.copytree(v2, out)
    m = json.loads((out / "manifest.json").read_text())
    assert m["tile_files"] == ["tiles-00000.bin"]  # one painting
    os.rename(out / "tiles-00000.bin", out / "tiles.bin")
    tiles = bytearray((out / "tiles.bin").read_bytes())
    tiles[8:12] = (1).to_bytes(4, "little")
    (out / "tiles.bin").write_bytes(tiles)
    raw, e = _entries(out)
    raw[8:12] = (1).to_bytes(4, "little")
    e = e.copy()
    for i in range(len(e)):
        o, n = int(e[i]["offset"]), int(e[i]["length"])
        e[i]["checksum"] = xxhash.xxh3_64_intdigest(bytes(tiles[o:o + n]))
    (out / "index.bin").write_bytes(bytes(raw[:32]) + e.tobytes())
    m["version"] = 1
    del m["tile_files"]
    (out / "manifest.json").write_text(json.dumps(m))
    return out


def test_v2_swapped_or_duplicated_entries_fail_verify_and_reads(small_pack, tmp_path):
    from gigascroll.cli import main
    from gigascroll.pack import verify_pack
    from gigascroll.pack.reader import PurePack
    path, img = small_pack
    assert TilePack(path).version == 2
    raw, e = _entries(path)
    for bad in ("swap", "duplicate"):
        f = e.copy()
        if bad == "swap":
            f[[1, 2]] = f[[2, 1]]
        else:
            f[2] = f[1]
        (path / "index.bin").write_bytes(bytes(raw[:32]) + f.tobytes())
        pack = TilePack(path)
        with pytest.raises(OSError, match="checksum mismatch"):
            verify_pack(pack)
        with pytest.raises(OSError, match="checksum mismatch in tile .painting 0, level 0, tile 2, 0"):
            pack.read_tile(0, 0, 2, 0)
        with pytest.raises(OSError, match="checksum mismatch"):
            PurePack(path).read_tile(0, 0, 2, 0)
        assert main(["info", str(path), "--verify"]) == 2


def test_v1_packs_still_read_with_a_warning(small_pack, tmp_path):
    from gigascroll.pack import verify_pack
    from gigascroll.pack.reader import PurePack
    path, img = small_pack
    v1 = make_v1_pack(path, tmp_path / "v1")
    with pytest.warns(UserWarning, match="version-1 pack.*cannot be detected"):
        pack = TilePack(v1)
    with pytest.warns(UserWarning, match="version-1 pack"):
        pure = PurePack(v1)
    v2 = TilePack(path)
    assert pack.version == 1 and pack.tile_files == ["tiles.bin"]
    assert verify_pack(pack) == v2.tile_count
    for l, (nx, ny) in enumerate(v2.paintings[0].level_tiles):
        for ty in range(ny):
            for tx in range(nx):
                t = v2.read_tile(0, l, tx, ty)
                assert np.array_equal(pack.read_tile(0, l, tx, ty), t)
                assert np.array_equal(pure.read_tile(0, l, tx, ty), t)
    # What version 1 cannot see: a swapped pair of entries reads as each other's tile.
    raw, e = _entries(v1)
    f = e.copy()
    f[[1, 2]] = f[[2, 1]]
    (v1 / "index.bin").write_bytes(bytes(raw[:32]) + f.tobytes())
    with pytest.warns(UserWarning):
        swapped = TilePack(v1)
    assert np.array_equal(swapped.read_tile(0, 0, 2, 0), v2.read_tile(0, 0, 1, 0))


@pytest.mark.parametrize("flags", [0, 2, 3, 0x101])
def test_flags_other_than_stored_are_oserror(small_pack, flags):
    from gigascroll.pack.reader import PurePack
    path, _ = small_pack
    raw, e = _entries(path)
    f = e.copy()
    f[3]["flags"] = flags
    (path / "index.bin").write_bytes(bytes(raw[:32]) + f.tobytes())
    pack = TilePack(path)
    p = pack.paintings[0]
    tx, ty = 3 % p.level_tiles[0][0], 3 // p.level_tiles[0][0]
    assert pack.has_tile(0, 0, tx, ty)
    for reader in (pack, PurePack(path)):
        with pytest.raises(OSError, match=f"flags {flags:#x}"):
            reader.read_tile(0, 0, tx, ty)
    assert np.array_equal(pack.read_tile(0, 0, 0, 0), PurePack(path).read_tile(0, 0, 0, 0))


def test_too_many_paintings_refused_before_any_work(tmp_path):
    from gigascroll._core import MAX_PACK_PAINTINGS
    assert MAX_PACK_PAINTINGS == 1 << 16
    img = np.zeros((2, 2, 3), np.uint8)
    with pytest.raises(ValueError, match="at most 65536 paintings"):
        gigascroll.build_pack([img] * (MAX_PACK_PAINTINGS + 1), tmp_path / "p", tile_size=4,
                              border=1)
    assert not (tmp_path / "p").exists()

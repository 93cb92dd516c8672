"""The pack as an open format: manifest.json against its JSON Schema, and the pure-Python
reader (numpy + xxhash + zstandard) against the core's reader on every stored tile."""

import copy
import json

import jsonschema
import numpy as np
import pytest

from gigascroll import TilePack, build_pack
from gigascroll.pack.reader import PurePack, manifest_schema, validate_manifest


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    """A raw and a zstd pack of two paintings (one grey, uint16) with odd sizes."""
    rng = np.random.default_rng(11)
    a = rng.integers(0, 256, (75, 131, 3), dtype=np.uint8)
    a[20:50, 10:90] = 40  # compressible area
    b = rng.integers(0, 65536, (33, 20), dtype=np.uint16)
    root = tmp_path_factory.mktemp("pure")
    return {codec: build_pack([a, b], root / codec, tile_size=16, border=2, codec=codec)
            for codec in ("raw", "zstd")}


def test_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(manifest_schema())


@pytest.mark.parametrize("codec", ["raw", "zstd"])
def test_written_manifest_validates(packs, codec):
    with open(f"{packs[codec].path}/manifest.json") as f:
        m = json.load(f)
    jsonschema.validate(m, manifest_schema(), cls=jsonschema.Draft202012Validator)
    validate_manifest(m)


@pytest.mark.parametrize("codec", ["raw", "zstd"])
def test_pure_reader_matches_core_on_every_tile(packs, codec):
    core = packs[codec]
    with PurePack(core.path) as pure:
        assert pure.codec == codec == core.codec
        assert (pure.tile_size, pure.border, pure.payload) == (core.tile_size, core.border, core.payload)
        assert pure.table_size == tuple(core.table_size)
        assert pure.tile_count == core.tile_count
        n = 0
        for i, (pp, cp) in enumerate(zip(pure.paintings, core.paintings, strict=True)):
            assert (pp.name, pp.width, pp.height, pp.source, pp.conversion) == \
                (cp.name, cp.width, cp.height, cp.source, cp.conversion)
            assert pp.colour == cp.colour
            assert pp.level_sizes == [tuple(s) for s in cp.level_sizes]
            assert pp.level_tiles == [tuple(t) for t in cp.level_tiles]
            assert pp.table_offset == tuple(cp.table_offset)
            for l, (nx, ny) in enumerate(pp.level_tiles):
                for ty in range(ny):
                    for tx in range(nx):
                        assert pure.locate(i, l, tx, ty) == tuple(core.locate(i, l, tx, ty))
                        np.testing.assert_array_equal(pure.read_tile(i, l, tx, ty),
                                                      core.read_tile(i, l, tx, ty))
                        n += 1
        assert n == core.tile_count


def _copy(pack, tmp_path):
    import shutil
    shutil.copytree(pack.path, tmp_path / "p")
    return tmp_path / "p"


# (mutation, the pure reader's message, whether the core's reader refuses it too: both apply
# the same rules, the colour record's fields included)
@pytest.mark.parametrize("mutate, message, core_refuses", [
    (lambda m: m.update(codec="lz4"), "schema at codec", True),
    (lambda m: m.update(version=3), "unsupported pack version 3", True),
    (lambda m: m.update(version=1.9), "schema at version", True),
    (lambda m: m["paintings"][0].pop("levels"), "schema at paintings/0", True),
    (lambda m: m["paintings"][0]["levels"][1].update(width=7), "level 1 of painting", True),
    (lambda m: m.update(tile_count=m["tile_count"] + 1), "tile_count does not match", True),
    (lambda m: m["paintings"][1]["page_table"].update(x=1), "unaligned or outside", True),
    (lambda m: m["paintings"][0].update(colour={"mode": "maybe"}), "schema at paintings/0/colour",
     True),
    (lambda m: m["paintings"][0].update(colour=[1]), "schema at paintings/0/colour", True),
    # Issue 11: values that wrapped 32-bit arithmetic or passed as the wrong type.
    (lambda m: m.update(border=2 ** 31), "schema at border", True),
    (lambda m: m["paintings"][0].update(width=2 ** 32 + 131), "schema at paintings/0/width", True),
    (lambda m: m.update(tile_size=16.0), "schema at tile_size", True),
    (lambda m: m["paintings"][0]["page_table"].update(x=0.0), "schema at paintings/0/page_table/x",
     True),
    (lambda m: m["page_table"].update(width=12), "schema at page_table/width", True),
    (lambda m: m["page_table"].update(width=2 ** 20, height=2 ** 20), "absurdly large", True),
    (lambda m: m["paintings"][1]["page_table"].update(x=m["paintings"][0]["page_table"]["x"],
                                                       y=m["paintings"][0]["page_table"]["y"]),
     "overlap", True),
    (lambda m: m["tile_files"].__setitem__(1, "../x.bin"), "schema at tile_files/1", True),
    (lambda m: m["tile_files"].__setitem__(1, "x.bin\n"), "tile_files", True),
    (lambda m: m.pop("tile_files"), "schema at", True),
    (lambda m: m["paintings"][0].update(uv_scale=[0.5, 0.5]), "uv_scale", True),
])
def test_both_readers_refuse_bad_manifests(packs, tmp_path, mutate, message, core_refuses):
    path = _copy(packs["raw"], tmp_path)
    m = json.loads((path / "manifest.json").read_text())
    bad = copy.deepcopy(m)
    mutate(bad)
    (path / "manifest.json").write_text(json.dumps(bad))
    with pytest.raises(OSError, match=message):
        PurePack(path)
    if core_refuses:
        with pytest.raises(OSError):
            TilePack(path)


def test_pure_reader_detects_damage(packs, tmp_path):
    path = _copy(packs["zstd"], tmp_path)
    core = TilePack(path)
    offset, length, _ = core.locate(0, 0, 1, 1)
    del core
    with open(path / "tiles-00000.bin", "r+b") as f:
        f.seek(offset + length // 2)
        byte = f.read(1)
        f.seek(offset + length // 2)
        f.write(bytes([byte[0] ^ 0xFF]))
    pure = PurePack(path)
    with pytest.raises(OSError, match="checksum mismatch"):
        pure.read_tile(0, 0, 1, 1)
    pure.read_tile(0, 0, 0, 0)  # the others still read
    with pytest.raises(ValueError, match="not stored"):
        pure.read_tile(0, 0, 99, 0)
    with pytest.raises(ValueError, match="out of range"):
        pure.read_tile(5, 0, 0, 0)
    pure.close()
    data = (path / "index.bin").read_bytes()
    (path / "index.bin").write_bytes(data[:-3])
    with pytest.raises(OSError, match="truncated"):
        PurePack(path)
    (path / "index.bin").write_bytes(b"NOTAPACK" + data[8:])
    with pytest.raises(OSError, match="magic"):
        PurePack(path)
    (path / "manifest.json").unlink()
    with pytest.raises(OSError, match="missing manifest"):
        PurePack(path)

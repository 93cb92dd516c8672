"""Exhibitions that mix image files and paintings of existing packs, or take several packs:
`exhibit build` merges the given packs' paintings into the show's pack (pack.merge) without
re-encoding a tile.

References: every level of every painting is compared sample for sample with the pack it
came from (read through the core's reader) and, for images, with a pack built from the image
alone; "not re-encoded" is checked on the files' bytes (the tile files are the source's,
hard-linked or byte-identical); instances against the manifest's instance_of and the pack's
byte count."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gigascroll.cli import main
from gigascroll.exhibit import ExhibitionError
from gigascroll.exhibit.build import build_show
from gigascroll.exhibit.show import open_show
from gigascroll.pack import build_pack, read_level
from gigascroll.pack.merge import merge_packs

from test_exhibit import cli_error

SETTINGS = dict(tile_size=64, border=2, codec="zstd")  # not the show's default: kept as given

SHOW = """
title = "Mixed"
[room]
walls = [[0, 0], [8, 0], [8, 5], [0, 5]]

[[paintings]]
title = "From an image"
image = "green.png"
width_cm = 50
height_cm = 40
hang = {{ wall = 0, along_m = 1.5 }}

[[paintings]]
title = "First of pack A"
pack = "a.pack"
painting = "{a0}"
width_cm = 60
height_cm = 36
hang = {{ wall = 0, along_m = 4.0 }}

[[paintings]]
title = "Second of pack A"
pack = "a.pack"
painting = 1
width_cm = 30
height_cm = 60
hang = {{ wall = 1, along_m = 2.0 }}

[[paintings]]
title = "Of pack B"
pack = "{b}"
painting = "only"
width_cm = 40
height_cm = 40
hang = {{ wall = 2, along_m = 3.0 }}
"""


def _noise(seed: int, h: int, w: int) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (h, w, 3), dtype=np.uint8)


@pytest.fixture
def mixed(tmp_path):
    Image.fromarray(_noise(1, 80, 100)).save(tmp_path / "green.png")
    build_pack([_noise(2, 150, 250), _noise(3, 200, 100)], tmp_path / "a.pack",
               names=["wide", "tall"], **SETTINGS)
    build_pack([_noise(4, 90, 90)], tmp_path / "b.pack", names=["only"], **SETTINGS)
    return tmp_path


def _write(d: Path, **subst) -> Path:
    values = {"a0": "wide", "b": "b.pack", **subst}
    (d / "show.toml").write_text(SHOW.format(**values))
    return d / "show.toml"


def _same_samples(pack_a, i, pack_b, j) -> None:
    pa, pb = pack_a.paintings[i], pack_b.paintings[j]
    assert (pa.width, pa.height, pa.levels) == (pb.width, pb.height, pb.levels)
    for level in range(pa.levels):
        assert np.array_equal(read_level(pack_a, i, level), read_level(pack_b, j, level)), level


def test_images_and_two_packs_make_one_show(mixed):
    from gigascroll.pack import TilePack
    record = build_show(_write(mixed), mixed / "show", iiif_base="http://localhost:8000/iiif")
    assert record["packed"] and sorted(record["merged_packs"]) == sorted(
        os.path.realpath(mixed / n) for n in ("a.pack", "b.pack"))
    show = open_show(mixed / "show")
    pack = show.pack
    assert (pack.tile_size, pack.border, pack.codec) == (64, 2, "zstd")
    names = [p.name for p in pack.paintings]
    a, b = TilePack(mixed / "a.pack"), TilePack(mixed / "b.pack")
    # Every sample as in the pack the painting came from.
    _same_samples(pack, names.index("first-of-pack-a"), a, 0)
    _same_samples(pack, names.index("second-of-pack-a"), a, 1)
    _same_samples(pack, names.index("of-pack-b"), b, 0)
    # The image: as a pack built from it alone with the same settings.
    alone = build_pack([str(mixed / "green.png")], mixed / "alone.pack", **SETTINGS)
    _same_samples(pack, names.index("from-an-image"), alone, 0)
    # Not re-encoded: the given packs' tile files are in the show's pack byte for byte.
    manifest = json.loads((Path(pack.path) / "manifest.json").read_text())
    for name, src in (("first-of-pack-a", mixed / "a.pack" / "tiles-00000.bin"),
                      ("of-pack-b", mixed / "b.pack" / "tiles-00000.bin")):
        f = Path(pack.path) / manifest["tile_files"][names.index(name)]
        assert f.read_bytes() == src.read_bytes()
    # The room shows every painting by its own name, and labels for all four (the show's
    # pack is its own).
    slots = [s.painting for s in show.room.paintings]
    assert slots[:4] == ["from-an-image", "first-of-pack-a", "second-of-pack-a", "of-pack-b"]
    assert slots[4:] == [f"label-{n}" for n in slots[:4]]
    assert all(s in names for s in slots)
    # The IIIF manifest lists the four paintings, each with its tiles exported.
    iiif = json.loads((mixed / "show" / "iiif" / "manifest.json").read_text())
    assert [next(iter(c["label"].values()))[0] for c in iiif["items"]] == [
        "From an image", "First of pack A", "Second of pack A", "Of pack B"]
    for n in slots[:4]:
        info = json.loads((mixed / "show" / "iiif" / n / "info.json").read_text())
        assert (info["width"], info["height"]) == (pack.paintings[names.index(n)].width,
                                                   pack.paintings[names.index(n)].height)


def test_second_build_reuses_and_a_changed_pack_is_merged_again(mixed):
    _write(mixed)
    assert build_show(mixed / "show.toml", mixed / "show")["packed"]
    second = build_show(mixed / "show.toml", mixed / "show")
    assert second["reused_pack"] and not second["packed"]
    build_pack([_noise(5, 90, 90)], mixed / "b.pack", names=["only"], force=True, **SETTINGS)
    third = build_show(mixed / "show.toml", mixed / "show")
    assert third["packed"]
    from gigascroll.pack import TilePack
    show = open_show(mixed / "show")
    names = [p.name for p in show.pack.paintings]
    _same_samples(show.pack, names.index("of-pack-b"), TilePack(mixed / "b.pack"), 0)


def test_a_pack_given_twice(mixed):
    """One pack by two paths, and one of its paintings shown twice: stored once, the other an
    instance; the pack holds each distinct painting's tiles once."""
    from gigascroll.pack import TilePack
    os.symlink(mixed / "a.pack", mixed / "a-again.pack")
    text = SHOW.format(a0="wide", b="a-again.pack").replace('painting = "only"', 'painting = 0')
    (mixed / "show.toml").write_text(text.replace("width_cm = 40\nheight_cm = 40",
                                                  "width_cm = 50\nheight_cm = 30"))
    build_show(mixed / "show.toml", mixed / "show")
    show = open_show(mixed / "show")
    m = json.loads((Path(show.pack.path) / "manifest.json").read_text())
    by = {p["name"]: p for p in m["paintings"]}
    assert "instance_of" in by["of-pack-b"] and "instance_of" not in by["first-of-pack-a"]
    assert m["paintings"][by["of-pack-b"]["instance_of"]]["name"] == "first-of-pack-a"
    a = TilePack(mixed / "a.pack")
    alone = build_pack([str(mixed / "green.png")], mixed / "alone.pack", **SETTINGS)
    distinct = sum(os.path.getsize(p) for p in (mixed / "a.pack").glob("tiles-*.bin")) + \
        os.path.getsize(mixed / "alone.pack" / "tiles-00000.bin")
    labels = sum(os.path.getsize(Path(show.pack.path) / m["tile_files"][i])
                 for i, p in enumerate(m["paintings"]) if p["name"].startswith("label-")
                 and "instance_of" not in p)
    assert m["tiles_bytes"] == distinct + labels
    names = [p.name for p in show.pack.paintings]
    _same_samples(show.pack, names.index("of-pack-b"), a, 0)
    _same_samples(show.pack, names.index("first-of-pack-a"), a, 0)
    del alone


def test_a_painting_missing_from_its_pack_is_one_line(mixed, capsys):
    f = _write(mixed, a0="nope")
    line = cli_error(capsys, ["exhibit", "build", str(f), "-o", str(mixed / "show"), "--no-bake"])
    assert line.startswith(f"gigascroll exhibit: error: {f}: paintings[1].painting: expected one of "
                           "the pack's paintings (wide, tall), got 'nope'"), line
    f = _write(mixed, b="missing.pack")
    line = cli_error(capsys, ["exhibit", "build", str(f), "-o", str(mixed / "show"), "--no-bake"])
    assert f"{f}: paintings[3].pack: expected an existing pack, 'missing.pack'" in line
    assert not (mixed / "show").exists()


def test_packs_of_different_settings_name_both(mixed, capsys):
    build_pack([_noise(4, 90, 90)], mixed / "b.pack", names=["only"], force=True)  # raw, 128
    f = _write(mixed)
    line = cli_error(capsys, ["exhibit", "build", str(f), "-o", str(mixed / "show"), "--no-bake"])
    assert (f"{f}: paintings[3].pack: expected a pack with paintings[1]'s pack's tile size, "
            "border and codec (tile 64, border 2, codec zstd;") in line
    assert "got tile 128, border 4, codec raw" in line
    assert not (mixed / "show").exists()


def test_merge_packs_verifies_and_reseeds(mixed):
    """merge_packs alone: a corrupt source tile is an OSError naming it (nothing written);
    the merged pack verifies tile by tile with the independent pure-Python reader."""
    from gigascroll.pack.reader import PurePack
    out = merge_packs([("b", mixed / "b.pack", 0), ("a1", mixed / "a.pack", "tall")],
                      mixed / "m.pack")
    with PurePack(out.path) as pure:
        for p in range(2):
            pp = pure.paintings[p]
            for level, (nx, ny) in enumerate(pp.level_tiles):
                for ty in range(ny):
                    for tx in range(nx):
                        pure.read_tile(p, level, tx, ty)  # checksums seeded with the new key
    tiles = mixed / "a.pack" / "tiles-00001.bin"
    data = bytearray(tiles.read_bytes())
    data[40] ^= 0xFF
    tiles.unlink()  # a new inode: the merged pack's hard link keeps the good bytes
    tiles.write_bytes(bytes(data))
    with pytest.raises(OSError, match=r"a\.pack: checksum mismatch in tile \(painting 1, level 0"):
        merge_packs([("x", mixed / "a.pack", 1)], mixed / "bad.pack")
    assert not (mixed / "bad.pack").exists()
    assert not list(mixed.glob("bad.pack.tmp-*"))
    with pytest.raises(ValueError, match="given twice"):
        merge_packs([("x", mixed / "b.pack", 0), ("x", mixed / "b.pack", 0)], mixed / "c.pack")
    with pytest.raises(ValueError, match=r"has paintings 0\.\.0, not 3"):
        merge_packs([("x", mixed / "b.pack", 3)], mixed / "c.pack")


def test_an_old_version_1_pack_merges_into_version_2(mixed):
    """A version-1 pack (one tiles.bin, unseeded checksums) gives its painting's tiles, cut
    into a tile file of its own, with every checksum seeded for the new key; the samples are
    the source's."""
    import warnings

    from gigascroll.pack import TilePack
    from gigascroll.pack.reader import PurePack
    from test_pack_reader import make_v1_pack
    v1 = make_v1_pack(mixed / "b.pack", mixed / "old.pack")
    out = merge_packs([("a", mixed / "a.pack", 0), ("old", v1, "only")], mixed / "m.pack")
    assert out.version == 2 and len(out.tile_files) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        _same_samples(out, 1, TilePack(v1), 0)
    with PurePack(out.path) as pure:  # the independent reader checks the new checksums
        pp = pure.paintings[1]
        for level, (nx, ny) in enumerate(pp.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    pure.read_tile(1, level, tx, ty)


def test_a_given_packs_instances_stay_instances(mixed):
    """A pack whose painting "copy" is an instance of "wide": shown with an image, both are
    merged and "copy" stays an instance (no second copy of the tiles); shown alone (its
    source not in the show), "copy" brings its source's tiles as a stored painting."""
    from gigascroll.pack import TilePack
    src = build_pack([_noise(2, 150, 250)], mixed / "inst.pack", names=["wide"],
                     instances=[("copy", 0)], **SETTINGS)
    assert json.loads((mixed / "inst.pack" / "manifest.json").read_text())[
        "paintings"][1]["instance_of"] == 0
    out = merge_packs([("img", mixed / "a.pack", 1), ("w", mixed / "inst.pack", "wide"),
                       ("c", mixed / "inst.pack", "copy")], mixed / "m.pack")
    m = json.loads((Path(out.path) / "manifest.json").read_text())
    by = {p["name"]: p for p in m["paintings"]}
    assert "instance_of" in by["c"] and m["paintings"][by["c"]["instance_of"]]["name"] == "w"
    assert len(m["tile_files"]) == 2
    names = [p.name for p in out.paintings]
    _same_samples(out, names.index("c"), src, 1)
    alone = merge_packs([("c", mixed / "inst.pack", "copy")], mixed / "alone.pack")
    assert "instance_of" not in json.loads(
        (Path(alone.path) / "manifest.json").read_text())["paintings"][0]
    _same_samples(alone, 0, TilePack(mixed / "inst.pack"), 1)

"""Reading packs back (gigascroll.pack.inspect): whole levels, the manifest, the summary."""

import json

import numpy as np
from pack_reference import ref_level

import gigascroll
from gigascroll import TilePack


def test_read_level_reassembles_the_painting(small_pack):
    path, img = small_pack
    pack = TilePack(path)
    assert np.array_equal(gigascroll.read_level(pack, 0, 0), img)
    lvl1 = gigascroll.read_level(pack, 0, 1)
    assert np.abs(lvl1 - ref_level(img, 1)).max() <= 0.5


def test_manifest_and_summary_describe_the_pack(small_pack):
    # The manifest as the core parsed it is the file's JSON; the summary names the geometry
    # and each painting.
    path, img = small_pack
    m = gigascroll.pack_manifest(path)
    assert m == json.loads((path / "manifest.json").read_text())
    assert (m["tile_size"], m["border"], len(m["paintings"])) == (16, 2, 1)
    pack = TilePack(path)
    text = gigascroll.pack_summary(pack)
    assert f"tile 16 px (border 2, payload 12), {pack.tile_count} tiles" in text
    assert f"[0] {pack.paintings[0].name}: 70 x 50" in text
    assert gigascroll.verify_pack(pack) == pack.tile_count

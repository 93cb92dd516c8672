"""Fuzz: shows that mix images and packs (`exhibit build` merging packs) with random pack
entries (missing packs, wrong painting names or indices, hostile values, a pack given twice,
a pack of other settings, a damaged source pack), and `merge_packs` called with random
items. Every CLI case ends with exit 0, or exit 2 and one line naming the file (no
traceback, crash or hang, no show left behind); every API case with a pack or a
ValueError / OSError."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

_counter = itertools.count()

PAINTING = """
[[paintings]]
title = "P{i}"
{source}
width_cm = {w}
height_cm = {h}
hang = {{ wall = {wall}, along_m = 2.0 }}
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from gigascroll.pack import build_pack
    d = tmp_path_factory.mktemp("fuzz-merge")
    rng = np.random.default_rng(0)
    Image.fromarray(rng.integers(0, 256, (40, 50, 3), np.uint8)).save(d / "img.png")
    build_pack([rng.integers(0, 256, (40, 50, 3), np.uint8),
                rng.integers(0, 256, (50, 40, 3), np.uint8)], d / "a.pack", names=["x", "y"])
    build_pack([rng.integers(0, 256, (40, 50, 3), np.uint8)], d / "z.pack", names=["x"],
               codec="zstd")
    build_pack([rng.integers(0, 256, (40, 50, 3), np.uint8)], d / "bad.pack", names=["x"])
    tiles = d / "bad.pack" / "tiles-00000.bin"
    data = bytearray(tiles.read_bytes())
    data[-5] ^= 0x55
    tiles.write_bytes(bytes(data))
    (d / "notapack").mkdir()
    return d


SOURCES = st.sampled_from([
    'image = "img.png"', 'pack = "a.pack"', 'pack = "a.pack"\npainting = "x"',
    'pack = "a.pack"\npainting = 1', 'pack = "a.pack"\npainting = 2',
    'pack = "a.pack"\npainting = -1', 'pack = "a.pack"\npainting = "nope"',
    'pack = "./a.pack/"', 'pack = "z.pack"', 'pack = "bad.pack"', 'pack = "notapack"',
    'pack = "missing.pack"', 'pack = "img.png"', 'pack = ""', 'pack = 3',
    'pack = "a.pack"\npainting = 1e9', 'pack = "a.pack"\npainting = "\\u0000"',
    'pack = "a.pack"\nimage = "img.png"'])


@fuzz_settings(15)
@given(sources=st.lists(SOURCES, min_size=1, max_size=4), labels=st.booleans())
def test_random_mixed_shows(fork_worker, files, sources, labels):
    count_case("exhibit build with packs")
    n = next(_counter)
    text = f'labels = {"true" if labels else "false"}\n[room]\nwalls = [[0, 0], [9, 0], [9, 9], [0, 9]]\n'
    for i, s in enumerate(sources):
        w, h = (40, 50) if "painting = 1" in s and "1e9" not in s else (50, 40)
        text += PAINTING.format(i=i, source=s, w=w, h=h, wall=i)
    f = files / f"m{n}.toml"
    f.write_text(text)
    out = files / f"out{n}"
    argv = ["exhibit", "build", str(f), "-o", str(out), "--no-bake", "--no-iiif", "--threads", "1"]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {text}\n{o.describe()}"
    if o.code == 2:
        assert not out.exists() and str(f) in o.stderr, o.describe()


ITEM = st.tuples(st.sampled_from(["a", "b", "", "\x00", "a" * 300, 7]),
                 st.sampled_from(["a.pack", "z.pack", "bad.pack", "notapack", "missing", "img.png",
                                  "a.pack/../a.pack", 3]),
                 st.sampled_from([0, 1, 2, -1, "x", "y", "", None, True, 1 << 70, 1.5]))


@fuzz_settings(20)
@given(items=st.one_of(st.lists(ITEM, max_size=4), st.sampled_from([None, "a.pack", {}, 5])))
def test_random_merge_items(fork_worker, files, items):
    count_case("merge_packs items")
    n = next(_counter)
    code = ("import os\nfrom gigascroll.pack.merge import merge_packs\n"
            f"os.chdir({str(files)!r})\n"
            "try:\n"
            f"    merge_packs({items!r}, 'merged{n}.pack')\n"
            "except (ValueError, OSError) as e:\n"
            "    assert not os.path.exists('merged%d.pack')\n" % n +
            "    print('refused:', e)\n")
    o = fork_worker.run({"kind": "python", "code": code}, timeout=60)
    assert o.code == 0 and not o.timeout, f"{items!r}\n{o.describe()}"

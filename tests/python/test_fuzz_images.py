"""Fuzz: random and mutated image files into `gigascroll pack`. Seeds are small valid files
of the formats and layouts the packer reads (PNG, JPEG, strip and tiled TIFF, 16-bit, float,
signed, CMYK, grey + alpha); a case truncates, flips, overwrites or inserts bytes. The outcome
is exit 0 with a pack that opens and verifies, or exit 2 with one error line and nothing left
at the output path: never a traceback, a signal, a hang or half-written output."""

from __future__ import annotations

import os

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings, long_only  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

tifffile = pytest.importorskip("tifffile")
Image = pytest.importorskip("PIL.Image")


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz-image-seeds")
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (24, 33, 3), np.uint8)
    out = {}
    Image.fromarray(rgb).save(d / "a.png")
    Image.fromarray(rgb).save(d / "a.jpg", quality=80)
    tifffile.imwrite(d / "strip.tif", rgb, rowsperstrip=5)
    tifffile.imwrite(d / "tiled.tif", np.pad(rgb, ((0, 8), (0, 15), (0, 0))), tile=(16, 16),
                     compression="zlib")
    tifffile.imwrite(d / "u16.tif", (rgb.astype(np.uint16) * 257), photometric="rgb")
    tifffile.imwrite(d / "f32.tif", rgb.astype(np.float32) / 255, photometric="rgb")
    tifffile.imwrite(d / "s16.tif", (rgb.astype(np.int16) - 128) * 200, photometric="rgb")
    tifffile.imwrite(d / "cmyk.tif", rng.integers(0, 256, (12, 10, 4), np.uint8),
                     photometric="separated")
    Image.fromarray(np.dstack([rgb[:, :, 0], rgb[:, :, 1]]), "LA").save(d / "la.png")
    for p in d.iterdir():
        out[p.name] = p.read_bytes()
    return out


@st.composite
def mutated(draw, seeds):
    name = draw(st.sampled_from(sorted(seeds)))
    data = bytearray(seeds[name])
    for _ in range(draw(st.integers(0, 4))):
        op = draw(st.sampled_from(["truncate", "flip", "overwrite", "insert", "header"]))
        if not data:
            break
        i = draw(st.integers(0, len(data) - 1))
        if op == "truncate":
            del data[i:]
        elif op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "overwrite":
            chunk = draw(st.binary(min_size=1, max_size=8))
            data[i:i + len(chunk)] = chunk
        elif op == "insert":
            data[i:i] = draw(st.binary(min_size=1, max_size=32))
        else:  # the first bytes hold sizes and offsets: 0xff or 0x00 there
            j = draw(st.integers(0, min(64, len(data) - 1)))
            data[j] = draw(st.sampled_from([0x00, 0xFF, 0x7F, 0x80]))
    return name, bytes(data)


def _check(fork_worker, tmp_path_factory, case, family):
    name, data = case
    count_case(family)
    d = tmp_path_factory.mktemp("fuzz-image")
    src = d / f"in{os.path.splitext(name)[1]}"
    src.write_bytes(data)
    out = d / "p"
    argv = ["pack", str(src), "-o", str(out), "--tile-size", "16", "--border", "2",
            "--threads", "1"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": 3 << 30}, timeout=60)
    problem = cli_message_ok(o)
    assert problem is None, f"pack of a mutated {name} ({len(data)} bytes): {problem}\n{o.describe()}"
    assert not list(d.glob("p.tmp-*")), "temporary build directory left behind"
    if o.code == 0:
        v = fork_worker.run({"kind": "cli", "argv": ["info", "--verify", str(out)]}, timeout=60)
        assert v.code == 0, f"a pack built from a mutated {name} does not verify\n{v.describe()}"
    else:
        assert not out.exists(), "a failed build left output"


@fuzz_settings(40)
@given(data=st.data())
def test_fuzz_images(fork_worker, tmp_path_factory, seeds, data):
    _check(fork_worker, tmp_path_factory, data.draw(mutated(seeds)), "images")


@pytest.mark.fuzz
@long_only
@fuzz_settings(40, long_examples=2000, long=True)
@given(data=st.data())
def test_fuzz_images_long(fork_worker, tmp_path_factory, seeds, data):
    _check(fork_worker, tmp_path_factory, data.draw(mutated(seeds)), "images-long")


def test_every_seed_packs(fork_worker, tmp_path_factory, seeds):
    """The unmutated seeds are valid: each packs with exit 0 (the fuzz starts from real files)."""
    for name, data in seeds.items():
        _check(fork_worker, tmp_path_factory, (name, data), "images-seeds")

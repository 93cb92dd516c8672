"""Fuzz cases for the foveation of the gallery walk (hypothesis): Foveation's parameters, its
layout on any eye, the core's composite with any sizes, and `gigascroll gallery --fovea` with
hostile values, each case of the last in a forked child (fuzz_support.Worker). Each either
works (a well-formed layout, a finite image) or raises ValueError / exits 2 with one line."""

from __future__ import annotations

import math

import numpy as np
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gigascroll import _core
from gigascroll import views as v
from gigascroll.commands.gallery import parse_foveation
from gigascroll.errors import UserError
from gigascroll.walk.foveation import Foveation

anything = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 400),
                     st.none(), st.text(max_size=4), st.booleans())


@fuzz_settings(150)
@given(deg=anything, factor=anything, blend=anything, w=st.integers(1, 300),
       h=st.integers(1, 300), tan=st.floats(1e-3, 1e3))
def test_foveation_any_parameters_and_eye(deg, factor, blend, w, h, tan):
    count_case("foveation-layout")
    try:
        f = Foveation(deg, factor, blend)
    except ValueError:
        return
    cam = v.Camera((0, 0, 0), (0, 0, -1), (0, 1, 0), tan, tan * h / w, w, h)
    try:
        lay = f.layout(cam)
    except ValueError as e:
        assert "narrower" in str(e)
        assert math.tan(math.radians(deg) / 2) >= min(cam.tan_half_x, cam.tan_half_y)
        return
    assert 0 < lay.fovea_width <= w and 0 < lay.fovea_height <= h
    assert lay.x0 * 2 + lay.fovea_width == w and lay.y0 * 2 + lay.fovea_height == h
    assert lay.periphery.width * factor >= w and lay.periphery.height * factor >= h
    wt = lay.weight
    assert wt.shape == (lay.fovea_height, lay.fovea_width) and wt.min() >= 0 and wt.max() <= 1
    masks = lay.masks()
    assert sum(int(m.sum()) for m in masks.values()) == w * h
    if w * h <= 20000:
        rng = np.random.default_rng(0)
        per = rng.random((lay.periphery.height, lay.periphery.width, 3), dtype=np.float32)
        fov = rng.random((lay.fovea_height, lay.fovea_width, 3), dtype=np.float32)
        out = lay.composite(fov, per)
        assert out.shape == (h, w, 3) and np.all(np.isfinite(out))
        assert out.min() >= 0 and out.max() <= 1


@fuzz_settings(150)
@given(pw=st.integers(0, 40), ph=st.integers(0, 40), fw=st.integers(0, 40),
       fh=st.integers(0, 40), wx=st.integers(0, 41), wy=st.integers(0, 41),
       x0=st.integers(0, 2**32 - 1), y0=st.integers(0, 50), factor=st.integers(0, 2**32 - 1),
       width=st.integers(0, 2**32 - 1), height=st.integers(0, 100))
def test_core_composite_any_sizes(pw, ph, fw, fh, wx, wy, x0, y0, factor, width, height):
    count_case("foveation-composite")
    per = np.ones((ph, pw, 3), np.float32)
    fov = np.zeros((fh, fw, 3), np.float32)
    try:
        out = _core._composite_foveated(per, fov, np.ones(wx, np.float32),
                                        np.ones(wy, np.float32), x0, y0, factor, width, height)
    except ValueError:
        return
    assert out.shape == (height, width, 3) and np.all(np.isfinite(out))


HOSTILE_DEG = ["nan", "inf", "-inf", "0", "-30", "95", "180", "1e400", "x", ""]
HOSTILE_FACTOR = ["0", "1", "-2", "17", "99999999999999999999", "nan", "2.5", ""]


@fuzz_settings(20)
@given(deg=st.sampled_from(HOSTILE_DEG + ["30"]), factor=st.sampled_from(HOSTILE_FACTOR + ["2"]))
def test_gallery_fovea_option_hostile_values(fork_worker, tmp_path_factory, deg, factor):
    if deg == "30" and factor == "2":
        return  # valid: a whole walk, covered by the gallery tests
    count_case("foveation-cli")
    out = tmp_path_factory.mktemp("fovea-cli") / "out"
    o = fork_worker.run({"kind": "cli", "argv": ["gallery", "--fovea", deg, "--fovea-factor",
                                                 factor, "--out", str(out)]}, timeout=60)
    problem = cli_message_ok(o)
    assert problem is None, f"--fovea {deg} --fovea-factor {factor}: {problem}\n{o.describe()}"
    assert o.code == 2 and not out.exists()


@fuzz_settings(100)
@given(deg=anything, factor=anything, w=st.integers(16, 4000), h=st.integers(16, 4000))
def test_parse_foveation_any_value(deg, factor, w, h):
    count_case("foveation-parse")
    try:
        f = parse_foveation(deg, factor, (w, h))
    except UserError as e:
        assert str(e).startswith("--fovea")
        return
    assert f is None or (0 < f.fovea_deg < 180 and 2 <= f.factor <= 16)


@fuzz_settings(20)
@given(deg=st.sampled_from(HOSTILE_DEG + ["30"]), factor=st.sampled_from(HOSTILE_FACTOR + ["2"]),
       eye=st.sampled_from([None, "16x16", "64x48", "1800x1920"]))
def test_view_fovea_option_hostile_values(fork_worker, tmp_path_factory, deg, factor, eye):
    """`gigascroll view --fovea`: bad values fail with the gallery's one-line message before
    the display or the pack is looked at; good ones get as far as the (missing) display."""
    count_case("foveation-view-cli")
    missing = tmp_path_factory.mktemp("fovea-view") / "no.pack"
    argv = ["view", str(missing), "--fovea", deg, "--fovea-factor", factor]
    if eye is not None:
        argv += ["--eye", eye]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=60)
    problem = cli_message_ok(o)
    assert problem is None, f"view {argv[2:]}: {problem}\n{o.describe()}"
    assert o.code == 2
    if deg == "30" and factor == "2":
        # No display in the fuzz worker (or, with one, no pack at that path).
        assert "display" in o.stderr or "not a tile pack" in o.stderr, o.describe()
    else:
        assert "--fovea" in o.stderr or "invalid" in o.stderr, o.describe()

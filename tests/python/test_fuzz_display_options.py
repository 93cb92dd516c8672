"""--exposure and --tone on every command that writes or shows an image (render, gallery, view,
serve, demo): bad values are one line and exit 2, with no output left behind; random --exposure
text gives exit 0 with an image or exit 2 with one line; the Python API (ExposureSetting,
Display, to_srgb8) raises ValueError on bad input and maps any float radiance, NaN and
infinities included, to valid codes. CLI cases run in forked children (fuzz_support)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

import gigascroll as g
from gigascroll.display_mapping import Display, ExposureSetting, to_srgb8

BAD_EXPOSURE = ["", "nan", "inf", "-inf", "white=", "white=0lux", "white=-1lux", "white=nanlux",
                "white=1e30lux", "1e6", "-100", "six", "white=200cd", "ev=6", "auto2",
                "white=200luxx", "0x10", "white=200 lux lux"]
BAD_TONE = ["", "aces", "agx", "Neutral", "clip-srgb", "neutral-srgb", "none"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("display_opts")
    g.build_pack(np.full((40, 600, 3), 180, np.uint8), d / "s.pack", tile_size=32, border=2)
    return d


def commands(files):
    """argv (without the display options) of each command that writes or shows an image,
    and the output it must not leave behind."""
    pack = str(files / "s.pack")
    return {
        "render scene": (["render", "cornell", "--width", "8", "--height", "8", "-o",
                          str(files / "scene.png")], files / "scene.png"),
        "render room": (["render", "--room", "scroll", "--pack", pack, "--width", "8",
                         "--height", "8", "--photons", "1000", "-o", str(files / "room.png")],
                        files / "room.png"),
        "gallery": (["gallery", pack, "--eye", "16x16", "--seconds", "0.05", "--no-video",
                     "--out", str(files / "walk")], files / "walk"),
        "view": (["view", pack, "--quit-after", "0.1"], None),
        "serve": (["serve", pack, "--room", "scroll", "--port", "0"], None),
        "demo": (["demo", "--workdir", str(files / "demo"), "--width", "3000", "--height", "120",
                  "--no-stream", "--no-walk"], files / "demo"),
    }


IMAGE_COMMANDS = ("render scene", "render room", "gallery", "view", "serve", "demo")
BAD = [(c, ["--exposure", e], "--exposure") for c in IMAGE_COMMANDS for e in BAD_EXPOSURE[:6]]
BAD += [("render room", ["--exposure", e], "--exposure") for e in BAD_EXPOSURE[6:]]
BAD += [(c, ["--tone", t], "--tone") for c in IMAGE_COMMANDS for t in BAD_TONE[:3]]
BAD += [("render room", ["--tone", t], "--tone") for t in BAD_TONE[3:]]


@pytest.mark.parametrize("command, options, match", BAD,
                         ids=[f"{c} {' '.join(o)}" for c, o, _ in BAD])
def test_bad_display_option_is_one_line_and_exit_2(fork_worker, files, command, options, match):
    count_case("display options bad input")
    argv, out = commands(files)[command]
    o = fork_worker.run({"kind": "cli", "argv": argv + options}, timeout=60)
    assert o.code == 2 and cli_message_ok(o) is None, o.describe()
    assert re.search(match, o.stderr), o.stderr
    assert out is None or not out.exists()


@given(text=st.one_of(st.text(max_size=24), st.from_regex(r"white=-?[0-9.e+]{0,8}(lux|lx)?",
                                                           fullmatch=True),
                      st.floats(allow_nan=True, allow_infinity=True).map(repr)))
@fuzz_settings(examples=12)
def test_random_exposure_text_renders_or_is_refused(fork_worker, files, text):
    count_case("display options random --exposure")
    out = files / "random.png"
    out.unlink(missing_ok=True)
    argv = ["render", "cornell", "--width", "8", "--height", "8", "--photons", "1000",
            "--exposure", text, "-o", str(out)]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=60)
    assert cli_message_ok(o) is None, o.describe()
    try:
        ExposureSetting.parse(text)
        valid = not text.startswith("-")  # argparse reads a leading '-' as an option
    except ValueError:
        valid = False
    if valid:
        assert o.code == 0 and out.is_file(), o.describe()
    else:
        assert o.code == 2 and not out.exists(), o.describe()


@given(text=st.text(max_size=40))
@fuzz_settings(examples=200)
def test_exposure_parse_raises_value_error_only(text):
    count_case("display options parse")
    try:
        s = ExposureSetting.parse(text)
    except ValueError as e:
        assert "\n" not in str(e) and len(str(e)) < 200
        return
    d = s.display(200.0)
    assert np.isfinite(d.exposure) and d.exposure > 0


@given(values=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32), min_size=3,
                       max_size=30),
       exposure=st.floats(min_value=1e-6, max_value=1e6), tone=st.sampled_from(["neutral", "clip"]))
@fuzz_settings(examples=200)
def test_any_radiance_maps_to_codes(values, exposure, tone):
    count_case("display options radiance")
    n = len(values) // 3 * 3
    rad = np.array(values[:n], np.float32).reshape(-1, 3)
    with np.errstate(over="raise", invalid="raise", divide="raise"):  # none on the way
        out = to_srgb8(rad, exposure, tone)
    assert out.shape == rad.shape and out.dtype == np.uint8
    finite = np.isfinite(rad).all(axis=1) & (rad >= 0).all(axis=1)
    black = (np.nan_to_num(rad, nan=0.0, posinf=1.0, neginf=0.0) <= 0).all(axis=1)
    assert np.all(out[finite & black] == 0)


@pytest.mark.parametrize("kwargs", [{"exposure": 0.0}, {"exposure": -1.0},
                                    {"exposure": float("nan")}, {"exposure": float("inf")},
                                    {"tone": "aces"}, {"tone": ""}])
def test_bad_display_is_a_value_error(kwargs):
    with pytest.raises(ValueError):
        Display(**kwargs)
    if "tone" in kwargs:
        with pytest.raises(ValueError):
            to_srgb8(np.zeros((1, 3)), 1.0, kwargs["tone"])

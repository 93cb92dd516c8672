"""`gigascroll light`'s bad input: a missing or wrong pack, opening hours out of range or NaN,
an unknown category, hostile lights files, bad sizes and places: one line and exit 2, no
traceback, no report left behind. Random option combinations: exit 0 with a whole report, or
exit 2 with one line. Cases run in forked children (fuzz_support)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

import gigascroll as g

QUICK = ["--photons", "2000", "--samples", "16", "--threads", "1"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("lightcli")
    img = np.full((40, 600, 3), 180, np.uint8)
    g.build_pack(img, d / "s.pack", tile_size=32, border=2, names=["scroll"])
    (d / "notapack").mkdir()
    (d / "afile").write_text("x")
    good = [{"name": "spot", "centre": [6, 2.9, -1], "aim": [0, -1, 1], "width": 0.3,
             "height": 0.3, "kelvin": 3000, "lux": 50, "painting": "scroll"}]
    lights = {
        "good": good,
        "nan": '[{"centre": [NaN, 2.9, -1], "aim": [0, -1, 1], "width": 0.3, "height": 0.3, '
               '"lumens": 100}]',
        "notjson": "{[",
        "empty": [],
        "object": {"centre": [0, 0, 0]},
        "unknown_key": [{**good[0], "watts": 3}],
        "no_painting": [{**good[0], "painting": "nowhere"}],
        "cold": [{**good[0], "kelvin": 100}],
        "huge": [{**good[0], "width": 1e300}],
        "both": [{**good[0], "lumens": 100}],
        "behind": [{**good[0], "centre": [6, 1.5, 1.0], "aim": [0, 0, 1]}],
        "string_lux": [{**good[0], "lux": "50"}],
        "deep": "[" * 100000 + "]" * 100000,
        "dup": good + good,
        "same_target": good + [{**good[0], "name": "spot2", "lux": 500}],
        "walls": [{**good[0], "name": "walls"}],
        "panels_and_centre": [{**good[0], "panels": [{"centre": [6, 2.9, -1], "aim": [0, -1, 1],
                                                      "width": 0.3, "height": 0.3}]}],
        "bad_panel": [{"name": "p", "lumens": 100, "panels": [{"centre": [0, 1, 0]}]}],
    }
    for name, data in lights.items():
        (d / f"{name}.json").write_text(data if isinstance(data, str) else json.dumps(data))
    (d / "binary.json").write_bytes(b"\xff\xfe\x00garbage")
    return d


def run_light(fork_worker, files, *args, out="report", timeout=120):
    argv = ["light", *args, "-o", str(files / out)]
    return fork_worker.run({"kind": "cli", "argv": argv}, timeout=timeout)


BAD = [
    (["missing.pack"], "not a tile pack"),
    (["notapack"], "not a tile pack"),
    (["s.pack", "--hours-per-day", "-1"], "hours per day"),
    (["s.pack", "--hours-per-day", "25"], "hours per day"),
    (["s.pack", "--hours-per-day", "nan"], "finite"),
    (["s.pack", "--days-per-year", "nan"], "finite"),
    (["s.pack", "--days-per-year", "inf"], "finite"),
    (["s.pack", "--days-per-year", "-3"], "days per year"),
    (["s.pack", "--days-per-year", "400"], "days per year"),
    (["s.pack", "--category", "extreme"], "invalid choice"),
    (["s.pack", "--category", ""], "invalid choice"),
    (["s.pack", "--samples", "1"], "--samples"),
    (["s.pack", "--samples", "100000"], "--samples"),
    (["s.pack", "--photons", "0"], "--photons"),
    (["s.pack", "--bake-spacing", "nan"], "--bake-spacing"),
    (["s.pack", "--bake-spacing", "0"], "--bake-spacing"),
    (["s.pack", "--room", "nowhere.glb"], "--room"),
    (["s.pack", "--lighting", "unlit"], "invalid choice"),
    (["s.pack", "--lights", "missing.json"], "no such lights file"),
    (["s.pack", "--hours-per-day", "abc"], "invalid float"),
    (["s.pack", "--targets", "exact"], "invalid choice"),
    (["s.pack", "--light-samples", "0"], "--light-samples"),
    (["s.pack", "--light-samples", "100000"], "--light-samples"),
    (["s.pack", "--targets", "total", "--lights", "same_target.json"], "cannot be"),
] + [(["s.pack", "--lights", f"{name}.json"], match) for name, match in (
    ("nan", "not a number JSON allows"), ("notjson", "not a JSON lights file"),
    ("empty", "list of 1 to 1000"), ("object", "list of 1 to 1000"),
    ("unknown_key", "unknown keys"), ("no_painting", "no painting slot 'nowhere'"),
    ("cold", "colour temperature"), ("huge", "width must be positive"),
    ("both", "exactly one of lumens or lux"), ("behind", "crosses the plane|faces the points"),
    ("string_lux", "lux must be a number"), ("deep", "nested|lights"),
    ("binary", "not a JSON lights file"), ("dup", "given twice"), ("walls", "given twice"),
    ("panels_and_centre", "not both"), ("bad_panel", "panel 0: missing"))]


@pytest.mark.parametrize("args, match", BAD, ids=[" ".join(a[1:] or a) for a, _ in BAD])
def test_bad_input_is_one_line_and_exit_2(fork_worker, files, args, match):
    count_case("light bad input")
    if (files / "report").exists():  # left by a failed case before: start clean
        import shutil
        shutil.rmtree(files / "report")
    o = run_light(fork_worker, files, *QUICK, *[str(files / a) if a.endswith(
        (".pack", ".json", "apack")) else a for a in args])
    assert o.code == 2 and cli_message_ok(o) is None, o.describe()
    import re
    assert re.search(match, o.stderr), o.stderr
    assert not (files / "report").exists()


def test_an_existing_file_or_foreign_directory_is_not_replaced(fork_worker, files):
    o = run_light(fork_worker, files, str(files / "s.pack"), *QUICK, out="afile")
    assert o.code == 2 and cli_message_ok(o) is None and "not a directory" in o.stderr
    assert (files / "afile").read_text() == "x"
    foreign = files / "foreign"
    foreign.mkdir()
    (foreign / "keep.txt").write_text("mine")
    o = run_light(fork_worker, files, str(files / "s.pack"), *QUICK, out="foreign")
    assert o.code == 2 and cli_message_ok(o) is None, o.describe()
    assert (foreign / "keep.txt").read_text() == "mine"


def test_a_good_run_then_a_rerun_replaces_its_own_report(fork_worker, files):
    for _ in range(2):
        o = run_light(fork_worker, files, str(files / "s.pack"), "--lights",
                      str(files / "good.json"), *QUICK, out="mine")
        assert o.code == 0, o.describe()
    results = json.loads((files / "mine" / "light.json").read_text())
    assert results["lights"][0]["kelvin"] == 3000
    assert {"index.html", "light.json", "map000.png"} <= {p.name for p in (files / "mine").iterdir()}


OPTIONS = st.lists(st.sampled_from([
    ["--category", "high"], ["--category", "none"], ["--category", "medium"],
    ["--category", "x"], ["--hours-per-day", "0"], ["--hours-per-day", "24"],
    ["--hours-per-day", "-0.5"], ["--hours-per-day", "1e308"], ["--days-per-year", "366"],
    ["--days-per-year", "0"], ["--days-per-year", "nan"], ["--room", "hall"],
    ["--room", "scroll"], ["--room", "cave"], ["--lighting", "full"], ["--samples", "2"],
    ["--samples", "0"], ["--bake-spacing", "0.5"], ["--bake-spacing", "-1"],
    ["--photons", "1"], ["--photons", "-5"], ["--lights", "good.json"],
    ["--lights", "nan.json"], ["--lights", "behind.json"], ["--targets", "total"],
    ["--light-samples", "4"], ["--lights", "same_target.json"],
]), max_size=4)


@fuzz_settings(10)
@given(options=OPTIONS)
def test_random_option_combinations(fork_worker, files, options):
    count_case("light options")
    args = [files / a if a.endswith(".json") else a for o in options for a in o]
    o = run_light(fork_worker, files, *QUICK, str(files / "s.pack"), *map(str, args),
                  out="fuzz")
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {options}\n{o.describe()}"
    if o.code == 0:
        results = json.loads((files / "fuzz" / "light.json").read_text())
        assert results["paintings"] and (files / "fuzz" / "index.html").is_file()

"""Fuzz: `exhibit build` with randomly mutated exhibition files (lines dropped, values
replaced by hostile ones, bytes inserted, the file cut), and `render` / `gallery` with random
`--look-at` / `--distance` / `--exhibition` values. Every case ends with exit 0, or exit 2
and one line (no traceback, crash or hang); a failed build leaves no show behind."""

from __future__ import annotations

import json
import itertools
import re

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

from test_exhibit import SHOW, write_images

_counter = itertools.count()


@pytest.fixture(scope="module")
def show_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz-exhibit")
    write_images(d)
    Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(d / "tiny.png")
    (d / "show.toml").write_text(SHOW)
    from gigascroll.exhibit.build import build_show
    build_show(d / "show.toml", d / "show")
    return d


HOSTILE = ["-1", "0", "1e308", "-1e308", "nan", "inf", "-inf", '"x"', "[]", "{}", "true",
           "1979-05-27", '"../../etc/passwd"', '"tiny.png"', '"show"', "3", "0.001", "99999",
           '"\\u0000"', "[[0, 0], [1, 0]]", '"' + "a" * 3000 + '"']


@st.composite
def mutated(draw) -> str:
    lines = SHOW.splitlines()
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["drop", "value", "bytes", "cut", "dup", "key"]))
        k = draw(st.integers(0, len(lines) - 1))
        if kind == "drop":
            lines.pop(k)
        elif kind == "value":
            numbers = [m for m in re.finditer(r'-?\d+(\.\d+)?|"[^"]*"', lines[k])]
            if numbers:
                m = draw(st.sampled_from(numbers))
                lines[k] = lines[k][:m.start()] + draw(st.sampled_from(HOSTILE)) + lines[k][m.end():]
        elif kind == "bytes":
            pos = draw(st.integers(0, len(lines[k])))
            junk = draw(st.sampled_from(["[", "]", "=", "\"", "{", "\\", "\x00", "\u00e9", "#", "[[x]]"]))
            lines[k] = lines[k][:pos] + junk + lines[k][pos:]
        elif kind == "cut":
            lines = lines[:k]
        elif kind == "dup":
            lines.insert(k, lines[k])
        else:
            lines[k] = re.sub(r"^(\w+)", lambda m: m.group(1) + "_", lines[k])
        if not lines:
            break
    return "\n".join(lines) + "\n"


@fuzz_settings(20)
@given(text=mutated())
def test_mutated_exhibition_files(fork_worker, show_files, text):
    count_case("exhibit build mutations")
    n = next(_counter)
    f = show_files / f"m{n}.toml"
    f.write_text(text, encoding="utf-8", errors="surrogateescape")
    out = show_files / f"out{n}"
    argv = ["exhibit", "build", str(f), "-o", str(out), "--no-bake", "--threads", "1"]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {text[:2000]}\n{o.describe()}"
    if o.code == 2:
        assert not out.exists()
        assert str(f) in o.stderr or "argument" in o.stderr


LOOK = st.one_of(st.sampled_from(["Red study", "Blue study", "0", "1", "2", "-1", "99999999999",
                                  "red-study", "label-red-study", "", " ", "nan", "1e9", "Red",
                                  "\u00e9", "a" * 5000]),
                 st.text(max_size=30))
DISTANCE = st.one_of(st.none(), st.sampled_from(["0", "-1", "nan", "inf", "1e308", "0.05",
                                                 "2", "1000", "x"]))


@fuzz_settings(15)
@given(look=LOOK, distance=DISTANCE, command=st.sampled_from(["render", "gallery"]),
       extra=st.sampled_from([[], ["--camera", "1,1.6,2,1,1.5,0"], ["--room", "hall"],
                              ["--tour", "nope.json"], ["--path", "walk"]]))
def test_random_look_at(fork_worker, show_files, look, distance, command, extra):
    count_case("--look-at values")
    if "\x00" in look:
        look = look.replace("\x00", "")
    n = next(_counter)
    argv = [command, "--exhibition", str(show_files / "show"), f"--look-at={look}"]
    if distance is not None:
        argv.append(f"--distance={distance}")
    if command == "render":
        argv += ["--lighting", "unlit", "--width", "16", "--height", "12", "-o",
                 str(show_files / f"s{n}.png")]
        extra = [] if extra in (["--tour", "nope.json"], ["--path", "walk"]) else extra
    else:
        argv += ["--eye", "16x16", "--seconds", "0.05", "--no-video", "--no-oracle",
                 "--lighting", "full", "--photons", "500", "--out", str(show_files / f"w{n}")]
        extra = [] if extra and extra[0] == "--camera" else extra
    argv += extra
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"


@pytest.mark.parametrize("target", ["", "nope", "show.toml", "show/paintings.pack", "show"])
def test_exhibition_option_values(fork_worker, show_files, target):
    argv = ["render", "--exhibition", str(show_files / target) if target else "", "--width",
            "8", "--height", "8", "--lighting", "unlit", "-o", str(show_files / "e.png")]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"
    assert (o.code == 0) == (target == "show")


@pytest.mark.parametrize("options", [
    ["--record-tour", "x.txt"], ["--record-tour", "{m}.json"], ["--record-tour", "nodir/t.json"],
    ["--record-tour", "t-{n}.json"], ["--record-tour", "{n:9999}.json"], ["--record-tour", ""],
    ["--look-at", "Red study", "--distance", "nan"], ["PACK"], [],
])
def test_view_options_fail_before_the_window(fork_worker, show_files, options):
    # Without a display every case ends with exit 2 and one line, bad options named first.
    options = [str(show_files / "show" / "paintings.pack") if o == "PACK" else o for o in options]
    argv = ["view", "--exhibition", str(show_files / "show"), *options]
    code = ("import os\nfor k in ('DISPLAY', 'WAYLAND_DISPLAY'):\n    os.environ.pop(k, None)\n"
            f"from gigascroll import cli\nraise SystemExit(cli.main({argv!r}))\n")
    o = fork_worker.run({"kind": "python", "code": code}, timeout=60)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"
    assert o.code == 2


@pytest.mark.parametrize("options", [
    ["--exhibition", "nope"], ["--exhibition", "SHOW", "PACK"], ["--exhibition", "SHOW", "--room", "hall"],
    [], ["PACK"], ["--exhibition", "SHOW", "--port", "70000"], ["--exhibition", ""],
])
def test_serve_exhibition_misuse(fork_worker, show_files, options):
    subst = {"SHOW": str(show_files / "show"), "PACK": str(show_files / "show" / "paintings.pack")}
    argv = ["serve", *[subst.get(o, o) for o in options]]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=60)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"
    assert o.code == 2


BASE_URL = st.one_of(st.sampled_from(["http://localhost:8000/iiif", "https://x.example/a b",
                                      "ftp://x/y", "", "http://", "/relative", "http://[::1",
                                      "http://x/\x00", "javascript:alert(1)", "http://x/" + "a" * 3000]),
                     st.text(max_size=40))


@fuzz_settings(12)
@given(base=BASE_URL)
def test_random_iiif_base_urls(fork_worker, show_files, base):
    count_case("exhibit build --base-url")
    n = next(_counter)
    out = show_files / f"iiif{n}"
    argv = ["exhibit", "build", str(show_files / "show.toml"), "-o", str(out), "--no-bake",
            "--threads", "1", f"--base-url={base}"]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {base!r}\n{o.describe()}"
    if o.code == 2:
        assert not out.exists()
    else:
        assert json.loads((out / "iiif" / "manifest.json").read_text())["id"].endswith("/manifest.json")


@pytest.mark.parametrize("workers", ["-1", "1025", "x", "1e3", "nan", ""])
def test_bad_workers_values(fork_worker, show_files, workers):
    out = show_files / f"workers{next(_counter)}"
    argv = ["exhibit", "build", str(show_files / "show.toml"), "-o", str(out), "--no-bake",
            "--no-iiif", f"--workers={workers}"]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    assert cli_message_ok(o) is None, o.describe()
    assert o.code == 2 and not out.exists()

"""Fuzz: random arguments for every `gigascroll` subcommand (those registered in
cli.COMMANDS, found through the parser, so new subcommands are covered automatically). The
outcome must be exit code 0, or 2 with one error line: never a traceback, a signal or a
hang. Each case runs in a forked child (fuzz_support.Worker)."""

from __future__ import annotations

import argparse
import json
import os

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings, long_only  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gigascroll import build_pack, cli

# Size-like options: a small value unless the case makes them hostile, so a valid case stays
# cheap (defaults are gallery-sized).
SMALL = {"width": 48, "height": 24, "photons": 256, "tiles": 50, "samples": 100, "frames": 2,
         "latency_frames": 2, "repeats": 1, "repeat": 1, "passes": 1, "spp": 1, "copies": 1,
         "pixels": 16, "pool": 8, "k": 4, "reference_spp": 1, "error_size": 8, "threads": 1,
         "duration": 0.05, "time_budget": 0.2, "tile_size": 16, "border": 2, "quality": 50}
HOSTILE_INTS = ["-1", "0", "-9223372036854775809", "18446744073709551616",
                "99999999999999999999999", "2147483648", "4294967297", "1e23", "nan", "", "0x10",
                "9" * 400]
HOSTILE_FLOATS = ["nan", "inf", "-inf", "-1", "1e308", "0", "1e-320", "1e23", "x"]
HOSTILE_TEXT = ["", "-", "\udcff\udcfe", "a" * 5000, "../../x", "💥", "none,none", ":"]
# Inputs in other branches' scope, kept out of the default families (listed in the report).
# serve runs until a signal: its own family is test_fuzz_serve.py's.
SKIP: list[tuple[str, ...]] = [("serve ", "--room")]


def subcommands(parser=None, prefix=()):
    """(argv prefix, subparser) for every leaf subcommand."""
    parser = parser or cli.build_parser()
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sp in a.choices.items():
                yield from subcommands(sp, prefix + (name,))
            return
    yield prefix, parser


LEAVES = list(subcommands())


def test_every_registered_command_is_fuzzed():
    tops = {p[0] for p, _ in LEAVES}
    registered = set()
    for m in cli.COMMANDS:  # each module registers at least one subcommand
        sub = argparse.ArgumentParser().add_subparsers()
        m.register(sub)
        registered |= set(sub.choices)
    assert registered == tops and len(LEAVES) >= len(cli.COMMANDS)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Paths a hostile user would hand over, by kind."""
    d = tmp_path_factory.mktemp("fuzz-cli-files")
    img = np.random.default_rng(0).integers(0, 256, (20, 30, 3), np.uint8)
    build_pack(img, d / "pack", tile_size=16, border=2)
    from PIL import Image
    Image.fromarray(img).save(d / "small.png")
    bad_name = os.fsencode(str(d)) + b"/caf\xe9-\xff.png"  # not UTF-8
    with open(bad_name, "wb") as f:
        f.write((d / "small.png").read_bytes())
    (d / "garbage.bin").write_bytes(os.urandom(300))
    (d / "deep.json").write_text("[" * 100000 + "]" * 100000)
    (d / "deep-object.json").write_text('{"a":' * 50000 + "1" + "}" * 50000)
    (d / "manifest-dir").mkdir()
    (d / "manifest-dir" / "manifest.json").mkdir()
    (d / "empty").mkdir()
    (d / "path.json").write_text(json.dumps({"frames": [{"t": 0, "position": [0, 1.6, 2],
                                                         "target": [0, 1.6, 0],
                                                         "magnifier_target": [0, 1.6, 0]}]}))
    return {"pack": str(d / "pack"), "image": str(d / "small.png"),
            "badname": os.fsdecode(bad_name), "garbage": str(d / "garbage.bin"),
            "deep": str(d / "deep.json"), "deep-object": str(d / "deep-object.json"),
            "manifest-dir": str(d / "manifest-dir"), "empty": str(d / "empty"),
            "missing": str(d / "missing"), "path": str(d / "path.json"), "dir": str(d)}


def _is_output(a) -> bool:
    return a.dest in ("output", "out", "workdir", "cache") or "out" in a.dest


def _kind(a) -> str:
    t = a.type
    if a.choices is not None:
        return "choice"
    if t is int:
        return "int"
    if t is float:
        return "float"
    if a.nargs == 0:
        return "flag"
    return "text"


@st.composite
def cli_case(draw, files, outdir):
    prefix, parser = draw(st.sampled_from(LEAVES))
    argv = list(prefix)
    positionals = []
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        kind = _kind(a)
        hostile = draw(st.integers(0, 3)) == 0
        if _is_output(a):
            value = str(outdir / f"out-{draw(st.integers(0, 3))}")
            if hostile:
                value = draw(st.sampled_from([files["pack"], files["garbage"], files["dir"],
                                              files["manifest-dir"], "", files["badname"]]))
        elif kind == "flag":
            if draw(st.booleans()):
                argv.append(a.option_strings[0])
            continue
        elif kind == "int":
            value = (draw(st.sampled_from(HOSTILE_INTS)) if hostile else
                     str(SMALL.get(a.dest, draw(st.integers(0, 3)))))
        elif kind == "float":
            value = (draw(st.sampled_from(HOSTILE_FLOATS)) if hostile else
                     str(SMALL.get(a.dest, draw(st.sampled_from([0.1, 0.5, 1.0])))))
        elif kind == "choice":
            value = (draw(st.sampled_from(HOSTILE_TEXT)) if hostile else
                     str(draw(st.sampled_from(list(a.choices)))))
        else:  # text: often a file of some kind
            pool = [files[k] for k in ("pack", "image", "badname", "garbage", "deep",
                                       "deep-object", "manifest-dir", "empty", "missing", "path")]
            value = draw(st.sampled_from(pool + HOSTILE_TEXT)) if hostile or not a.option_strings \
                else None
            if value is None:
                if a.default is not None and not a.required and draw(st.booleans()):
                    continue  # keep the default
                value = draw(st.sampled_from(pool))
        if not a.option_strings:  # positional
            n = 1 if a.nargs in (None, 1) else draw(st.integers(1, 3))
            values = [value] + [draw(st.sampled_from([files["image"], files["badname"],
                                                      files["garbage"]])) for _ in range(n - 1)]
            positionals.extend(values)
            continue
        if not a.required and not hostile and a.dest not in SMALL and draw(st.booleans()):
            continue  # leave it at its default
        if a.dest in SMALL or a.required or hostile or draw(st.booleans()):
            argv += [a.option_strings[-1], value]
    if "--quick" in parser._option_string_actions and draw(st.integers(0, 4)) > 0:
        argv.append("--quick")
    if "--no-render" in parser._option_string_actions:
        argv.append("--no-render")
    if "--force" in parser._option_string_actions and draw(st.booleans()):
        argv.append("--force")
    return argv + ["--"] + positionals if positionals else argv


def _check_cases(fork_worker, files, tmp_path_factory, data, family):
    outdir = tmp_path_factory.mktemp("fuzz-cli-out")
    argv = data.draw(cli_case(files, outdir))
    if any(all(s in " ".join(argv) for s in pattern) for pattern in SKIP):
        return
    count_case(family)
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": 6 << 30}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"gigascroll {argv!r}: {problem}\n{o.describe()}"


@fuzz_settings(100)
@given(data=st.data())
def test_fuzz_cli(fork_worker, files, tmp_path_factory, data):
    _check_cases(fork_worker, files, tmp_path_factory, data, "cli")


@pytest.mark.fuzz
@long_only
@fuzz_settings(100, long_examples=2000, long=True)
@given(data=st.data())
def test_fuzz_cli_long(fork_worker, files, tmp_path_factory, data):
    _check_cases(fork_worker, files, tmp_path_factory, data, "cli-long")


@pytest.mark.parametrize("argv", [
    ["info", "{deep}"], ["info", "{manifest-dir}"], ["info", "--verify", "{deep-object}"],
    ["pack", "--seed", "-1", "-o", "{out}", "{image}"],
    ["pack", "--seed", "18446744073709551616", "-o", "{out}", "{image}"],
    ["pack", "--threads", "99999999999", "-o", "{out}", "{image}"],
    ["pack", "-o", "{out}", "{badname}"],
    ["render", "cornell", "-o", "{out}.png", "--photons", "1e23"],
    ["render", "cornell", "-o", "{out}.png", "--photons", "99999999999999999999"],
    ["render", "cornell", "-o", "{out}.png", "--width", "99999999999", "--photons", "10"],
    ["render", "cornell", "-o", "{out}.png", "--threads", "99999999999", "--photons", "10"],
    ["render", "cornell", "-o", "{out}.png", "--width", "30000", "--height", "30000",
     "--photons", "10"],  # more than the case's 4 GB: one line, not a MemoryError traceback
    ["render", "cornell", "-o", "{out}.png", "--camera", "1e308,0,0,-1e308,0,0", "--photons", "10"],
    ["render", "cornell", "-o", "{out}.png", "--camera", "0,5,0,0,0,0,179.99999", "--photons", "10"],
    ["render", "cornell", "-o", "{out}.png", "--camera", "0,0,3,0,0,0,1e-300", "--photons", "10"],
    ["synth", "-o", "{out}.tif", "--width", "99999999999"],
    ["synth", "-o", "{out}.tif", "--seed", "-5", "--width", "40", "--height", "20"],
    ["scenario", "single", "--quick", "--path", "{path}", "--pack", "{pack}", "--out", "{out}"],
    ["scenario", "single", "--quick", "--path", "{deep}", "--out", "{out}"],
])
def test_known_hostile_cli_inputs(fork_worker, files, tmp_path, argv):
    """The inputs of issue 11 §6, one by one: exit 0 or one line with exit code 2."""
    names = dict(files, out=str(tmp_path / "out"))
    argv = [a.format(**names) if "{" in a else a for a in argv]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"gigascroll {argv!r}: {problem}\n{o.describe()}"

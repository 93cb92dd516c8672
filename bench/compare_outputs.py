#!/usr/bin/env python3
"""Proves that two gigascroll checkouts produce the same outputs, and compares their speed.

    python bench/compare_outputs.py --old REV_OR_DIR [--new REV_OR_DIR] [--work DIR]
                                    [--speed] [--pairs N] [--full]

--old / --new name a git revision of this repository (a worktree of it is made under
--work/checkouts and built with `make build`, or reused if already built) or a directory that
is a built checkout (has .venv/bin/gigascroll). --new defaults to this checkout. --work
defaults to build/compare in this checkout.

Each checkout runs the same commands through its own .venv/bin/gigascroll (only the CLI, so
any layout of the package works), in its own output directory but from a working directory
at the same depth, so relative paths recorded in the outputs are the same. Compared:
  pack      synthesized TIFFs (pixels), packs of the old checkout's TIFFs (every file's sha256),
            `info --verify` output;
  scenario  `scenario NAME --quick --no-pace`: NAME.json without timing fields, frame PNGs;
  demo      a small `demo`: its TIFF, pack and the PNGs it writes;
  render    `render` of the built-in scenes at fixed seeds: pixels of the EXRs.
It prints a Markdown table, writes --work/compare.json and exits 0 when everything is
identical, 1 otherwise (or when a --speed benchmark run fails), 2 when a checkout is missing
or does not build.

--speed then times `bench views --part pace`, `bench loader` and `bench photon`, old and new
alternately (--pairs pairs), with settings that keep each run to a minute or two (--full: the
benchmarks' own defaults), and reports each headline figure's median new/old ratio.

Needs numpy and OpenImageIO: run it with a checkout's .venv/bin/python.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

try:
    import numpy as np
    import OpenImageIO as oiio
except ImportError as e:
    print(f"compare_outputs: error: {e.name} is missing; run with a checkout's .venv/bin/python",
          file=sys.stderr)
    sys.exit(2)

ROOT = Path(__file__).resolve().parents[1]

SCENARIOS = ("single", "multi", "sweep", "latency")
# Keys of scenario results that hold a measured time or rate (stage times, fps, time stamps,
# and `ms` / `cpu_ms` of the request-processing sweep). In quick runs nothing else depends on
# the clock: the loop waits for each frame's loads and is not paced.
TIMING_KEY = re.compile(r"(^|_)(ms|s|seconds|fps)$|^fps_|_ms_std$")
# cpu-async (Unreal SVT) deduplicates on a worker thread, and which frame's result is ready at
# each poll depends on thread scheduling: its commands, loads, hit rates and latencies differ
# between two runs of the same build. Of its rows only what the camera path fixes is compared.
ASYNC_STABLE_KEYS = {"method", "strategy", "frames", "paintings", "tiles", "width",
                     "requests_per_frame", "records", "frame", "requests", "moving"}
# The frames a scenario shows; its other PNGs plot timings and cpu-async curves.
SCENARIO_FRAMES = ("single_eye_*.png", "single_magnifier_*.png")
# Written by OpenImageIO at write time (EXR, TIFF).
FILE_TIME_ATTRS = {"DateTime"}
# Packages whose version can change the outputs compared here; a difference in any other
# package is only counted in the report (listed in compare.json).
OUTPUT_PACKAGES = ("numpy", "openimageio", "matplotlib", "pillow", "mitsuba", "drjit", "nanobind")

PACK_VARIANTS = [  # (item, output, arguments after `pack`)
    ("raw", "p.pack", ["in.tif"]),
    ("zstd, two inputs", "z.pack", ["in.tif", "in2.tif", "--codec", "zstd"]),
    ("shelf layout, tile 64, border 2", "s.pack",
     ["in.tif", "--layout", "shelf", "--tile-size", "64", "--border", "2"]),
]
SYNTH = [("in.tif", ["--width", "3000", "--height", "700", "--seed", "3"]),
         ("in2.tif", ["--width", "2000", "--height", "500", "--seed", "5"])]
DEMO_ARGS = ["--width", "24000", "--height", "1600"]
RENDERS = [  # (output, arguments after `render`)
    ("cornell.exr", ["cornell", "--photons", "100000"]),
    ("office.exr", ["office", "--photons", "50000"]),
    ("cornell_kdtree_knn.exr", ["cornell", "--photons", "100000", "--grid", "kdtree",
                                "--gather", "knn", "-k", "50"]),
    ("cornell_two_pass_cooperative_cone.exr",
     ["cornell", "--photons", "100000", "--pipeline", "two-pass", "--cooperative",
      "--kernel", "cone"]),
]
RENDER_COMMON = ["--width", "64", "--height", "64", "--seed", "7", "--spp", "2"]

# Benchmark settings. Short: about 15 s (pace: its one length; --frames does not reach it),
# 100 s (loader: a 12000 x 6083 painting, as high as the scroll so a frame requests the
# seed's ~220 tiles, 20000 tiles a run) and 70 s (photon: the Cornell box tables at full
# size; skipped are the error study, whose time is mostly Mitsuba's, and the C++ nanoflann
# Google Benchmark).
BENCH_SHORT = {
    "pace": ["bench", "views", "--part", "pace"],
    "loader": ["bench", "loader", "--width", "12000", "--height", "6083", "--tiles", "20000",
               "--repeat", "3"],
    "photon": ["bench", "photon", "--scenes", "cornell", "--skip", "error,nanoflann"],
}
BENCH_FULL = {"pace": ["bench", "views", "--part", "pace"], "loader": ["bench", "loader"],
              "photon": ["bench", "photon"]}
# Marks a figure that times no project code (a plain file read): it shows how much the
# machine's speed drifted between runs and is left out of the geometric mean.
CONTROL = "(control: sequential read)"


class SetupError(Exception):
    """A checkout that is missing or does not build: reported in one line, exit 2."""


@dataclass
class Checkout:
    label: str      # "old" or "new"
    spec: str       # as given on the command line
    root: Path
    commit: str
    dirty: bool

    @property
    def exe(self) -> Path:
        return self.root / ".venv" / "bin" / "gigascroll"


@dataclass
class Item:
    producer: str
    item: str
    identical: bool
    result: str
    details: dict = field(default_factory=dict)


@dataclass
class Run:
    rc: int
    seconds: float
    stdout: str
    log: Path


# ----------------------------------------------------------------------------- checkouts

def git(*args, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True)


def runs_cli(root: Path) -> bool:
    exe = root / ".venv" / "bin" / "gigascroll"
    return exe.exists() and subprocess.run([str(exe), "--help"], capture_output=True,
                                           env=clean_env()).returncode == 0


def describe(label: str, spec: str, root: Path) -> Checkout:
    head = git("rev-parse", "HEAD", cwd=root)
    status = git("status", "--porcelain", "--untracked-files=no", cwd=root)
    return Checkout(label, spec, root, head.stdout.strip() if head.returncode == 0 else "",
                    bool(status.stdout.strip()))


def locate(label: str, spec: str) -> Path | str:
    """A built checkout's directory, or the commit a git revision names."""
    path = Path(spec)
    if path.is_dir():
        if not (path / ".venv" / "bin" / "gigascroll").exists():
            raise SetupError(f"--{label} {spec}: not a built checkout (no .venv/bin/gigascroll; "
                             f"run `make build` there)")
        return path.resolve()
    sha = git("rev-parse", "--verify", "--quiet", f"{spec}^{{commit}}").stdout.strip()
    if not sha:
        raise SetupError(f"--{label} {spec}: neither a directory nor a git revision of {ROOT}")
    return sha


def prepare(label: str, spec: str, where: Path | str, work: Path) -> Checkout:
    """The checkout for locate()'s answer: a revision gets a worktree under work/checkouts,
    built with `make build` unless its CLI already runs."""
    if isinstance(where, Path):
        return describe(label, spec, where)
    sha = where
    tree = work / "checkouts" / sha[:12]
    if not tree.exists():
        tree.parent.mkdir(parents=True, exist_ok=True)
        made = git("worktree", "add", "--detach", str(tree), sha)
        if made.returncode != 0:
            raise SetupError(f"--{label} {spec}: git worktree add failed: "
                             f"{made.stderr.strip().splitlines()[-1]}")
    elif git("rev-parse", "HEAD", cwd=tree).stdout.strip() != sha:
        raise SetupError(f"--{label} {spec}: {tree} exists but is not a checkout of {sha[:12]}")
    if runs_cli(tree):
        progress(f"{label}: reusing the built worktree {tree} ({sha[:12]})")
    else:
        log = work / "logs" / f"build-{sha[:12]}.log"
        log.parent.mkdir(parents=True, exist_ok=True)
        progress(f"{label}: make build in {tree} (log {log}); this takes a while")
        t0 = time.perf_counter()
        with open(log, "w") as f:
            rc = subprocess.run(["make", "build"], cwd=tree, stdout=f, stderr=subprocess.STDOUT,
                                env=clean_env()).returncode
        if rc != 0 or not runs_cli(tree):
            raise SetupError(f"--{label} {spec}: make build failed in {tree} (see {log})")
        progress(f"{label}: built in {time.perf_counter() - t0:.0f} s")
    return describe(label, spec, tree)


# ----------------------------------------------------------------------------- running

START = time.perf_counter()


def progress(msg: str) -> None:
    m, s = divmod(int(time.perf_counter() - START), 60)
    print(f"[{m:3d}:{s:02d}] {msg}", flush=True)


def clean_env() -> dict:
    """The caller's environment without anything that would make a checkout import another
    checkout's modules; a fixed hash seed and a headless matplotlib for both."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP")}
    env.update(PYTHONHASHSEED="0", MPLBACKEND="Agg")
    return env


class Runner:
    """Runs a checkout's CLI in a directory, logging stdout and stderr, and keeps the time of
    every step."""

    def __init__(self, work: Path):
        self.work = work
        self.steps: list[dict] = []

    def side(self, co: Checkout, *parts: str) -> Path:
        return self.work / co.label / Path(*parts)

    def fresh(self, co: Checkout, *parts: str) -> Path:
        d = self.side(co, *parts)
        if d.exists():
            shutil.rmtree(d)
        d.mkdir(parents=True)
        return d

    def run(self, co: Checkout, producer: str, name: str, args: list[str], cwd: Path) -> Run:
        logs = self.side(co, "logs")
        logs.mkdir(parents=True, exist_ok=True)
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{producer}-{name}")
        out, err = logs / f"{stem}.out", logs / f"{stem}.log"
        t0 = time.perf_counter()
        with open(out, "w") as fo, open(err, "w") as fe:
            rc = subprocess.run([str(co.exe), *args], cwd=cwd, stdout=fo, stderr=fe,
                                env=clean_env()).returncode
        seconds = time.perf_counter() - t0
        self.steps.append({"producer": producer, "step": name, "side": co.label,
                           "seconds": round(seconds, 2), "rc": rc})
        progress(f"{producer} {name} ({co.label}): {seconds:.1f} s"
                 + ("" if rc == 0 else f", exit {rc} (see {err})"))
        return Run(rc, seconds, out.read_text(), err)


def failed_item(producer: str, item: str, runs: dict[str, Run]) -> Item | None:
    """An Item saying which side's command failed, or None when both succeeded."""
    bad = {k: r for k, r in runs.items() if r.rc != 0}
    if not bad:
        return None
    text = "; ".join(f"{k} exit {r.rc} (log {r.log})" for k, r in bad.items())
    return Item(producer, item, False, f"FAILED: {text}", {k: r.rc for k, r in runs.items()})


# ----------------------------------------------------------------------------- comparisons

def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def compare_dirs(producer: str, item: str, old: Path, new: Path) -> Item:
    """Every file of two output directories (a pack), byte for byte."""
    files = {p.name for d in (old, new) if d.is_dir() for p in d.iterdir()}
    if not files:
        return Item(producer, item, False, "DIFFERS: no output on either side")
    shas = {f: [sha256(d / f) if (d / f).is_file() else None for d in (old, new)]
            for f in sorted(files)}
    differ = [f for f, (a, b) in shas.items() if a != b or a is None]
    details = {f: {"old": a, "new": b} for f, (a, b) in shas.items()}
    if differ:
        text = []
        for f in differ:  # a JSON file (the manifest) says where it differs
            paths = (json_diff(*(json.loads((d / f).read_text()) for d in (old, new)))
                     if f.endswith(".json") and None not in shas[f] else [])
            details[f]["differing_paths"] = paths
            text.append(f"{f} at {', '.join(paths)}" if paths else f)
        return Item(producer, item, False, "DIFFERS: " + "; ".join(text), details)
    return Item(producer, item, True, f"identical bytes ({', '.join(shas)})", details)


def read_image(path: Path):
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise OSError(f"{path}: {oiio.geterror()}")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, spec.format)
        attrs = {p.name: str(p.value) for p in spec.extra_attribs}
    finally:
        inp.close()
    if pixels is None:
        raise OSError(f"{path}: {oiio.geterror()}")
    return np.asarray(pixels), str(spec.format), attrs


def compare_images(producer: str, item: str, old: Path, new: Path,
                   rows: slice | None = None) -> Item:
    """Pixels exactly (and metadata other than the file time); byte equality is reported.
    When pixels differ: max |diff|, differing pixels and relMSE against old (8-bit values
    taken as [0, 1], eps 1e-2 as in the project's relmse)."""
    for side, p in (("old", old), ("new", new)):
        if not p.is_file():
            return Item(producer, item, False, f"DIFFERS: no {p.name} from {side}")
    try:
        (a, fa, ma), (b, fb, mb) = read_image(old), read_image(new)
    except OSError as e:
        return Item(producer, item, False, f"DIFFERS: unreadable: {e}")
    if rows is not None:
        a, b = a[rows], b[rows]
    same_bytes = rows is None and sha256(old) == sha256(new)
    meta = sorted(k for k in (set(ma) | set(mb)) - FILE_TIME_ATTRS if ma.get(k) != mb.get(k))
    details = {"shape": list(a.shape), "format": fa, "bytes_identical": same_bytes}
    if a.shape != b.shape or fa != fb:
        return Item(producer, item, False, f"DIFFERS: {fa} {a.shape} vs {fb} {b.shape}", details)
    if a.dtype.kind == "f":
        same = (a == b) | (np.isnan(a) & np.isnan(b))
    else:
        same = a == b
    problems = []
    if not same.all():
        x, y = a.astype(np.float64), b.astype(np.float64)
        if a.dtype.kind in "ui":
            x, y = x / np.iinfo(a.dtype).max, y / np.iinfo(a.dtype).max
        d = np.abs(np.where(same, 0.0, y - x))
        rel = np.where(same, 0.0, (y - x) ** 2) / (x ** 2 + 1e-2)
        details.update(max_abs_diff=float(np.nanmax(d)),
                       differing_pixels=int((~same).any(axis=-1).sum()),
                       relmse=float(np.nanmean(rel)))
        problems.append(f"{details['differing_pixels']} of {a.shape[0] * a.shape[1]} pixels, "
                        f"max |diff| {details['max_abs_diff']:.3g}, relMSE {details['relmse']:.3g}")
    if meta:
        details["metadata_differs"] = {k: [ma.get(k), mb.get(k)] for k in meta}
        problems.append("metadata " + ", ".join(meta))
    if problems:
        return Item(producer, item, False, "DIFFERS: " + "; ".join(problems), details)
    if rows is not None:
        return Item(producer, item, True, "identical pixels", details)
    if same_bytes:
        return Item(producer, item, True, "identical pixels and bytes", details)
    stamps = [k for k in FILE_TIME_ATTRS if ma.get(k) != mb.get(k)]
    why = f" (file time {', '.join(stamps)})" if stamps else ""
    return Item(producer, item, True, f"identical pixels; bytes differ{why}", details)


def stable_results(x, dropped: set, async_row: bool = False):
    """Scenario results without timing fields and without cpu-async's scheduling-dependent
    fields (see TIMING_KEY, ASYNC_STABLE_KEYS); dropped keys are collected in `dropped`."""
    if isinstance(x, dict):
        async_row = async_row or (x.get("method") == "cpu-async" and "records" in x)
        out = {}
        for k, v in x.items():
            if TIMING_KEY.search(k):
                dropped.add(k)
            elif async_row and k not in ASYNC_STABLE_KEYS:
                dropped.add(f"{k} (cpu-async rows)")
            else:
                out[k] = stable_results(v, dropped, async_row)
        return out
    if isinstance(x, list):
        return [stable_results(v, dropped, async_row) for v in x]
    return x


def json_diff(a, b, path: str = "") -> list[str]:
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                out.append(f"{path}/{k} (only in {'new' if k in b else 'old'})")
            else:
                out += json_diff(a[k], b[k], f"{path}/{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path} (length {len(a)} vs {len(b)})"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in json_diff(x, y, f"{path}[{i}]")]
    return [] if a == b and type(a) is type(b) else [path or "/"]


def compare_results(producer: str, item: str, old: Path, new: Path) -> Item:
    for side, p in (("old", old), ("new", new)):
        if not p.is_file():
            return Item(producer, item, False, f"DIFFERS: no {p.name} from {side}")
    dropped: set = set()
    a = stable_results(json.loads(old.read_text()), dropped)
    b = stable_results(json.loads(new.read_text()), dropped)
    diffs = json_diff(a, b)
    details = {"ignored_keys": sorted(dropped), "differing_paths": diffs}
    if diffs:
        shown = ", ".join(diffs[:8]) + (f", ... ({len(diffs)} in all)" if len(diffs) > 8 else "")
        return Item(producer, item, False, f"DIFFERS at {shown}", details)
    return Item(producer, item, True, "identical (timing fields ignored)", details)


# ----------------------------------------------------------------------------- producers

def produce_pack(r: Runner, old: Checkout, new: Checkout) -> list[Item]:
    """Both synthesize the inputs (compared as pixels); both pack the old checkout's."""
    items = []
    runs = {co.label: {} for co in (old, new)}
    for co in (old, new):
        cwd = r.fresh(co, "synth")
        for name, args in SYNTH:
            runs[co.label][name] = r.run(co, "pack", f"synth {name}", ["synth", *args, "-o", name],
                                         cwd)
    for name, _ in SYNTH:
        fail = failed_item("pack", f"synth {name}", {k: v[name] for k, v in runs.items()})
        items.append(fail or compare_images("pack", f"synth {name}", r.side(old, "synth", name),
                                            r.side(new, "synth", name)))
    if any(run.rc for v in runs.values() for run in v.values()):
        return items
    for co in (old, new):
        cwd = r.fresh(co, "pack")
        for name, _ in SYNTH:
            shutil.copyfile(r.side(old, "synth", name), cwd / name)
        for _, out, args in PACK_VARIANTS:
            runs[co.label][out] = r.run(co, "pack", out, ["pack", *args, "-o", out], cwd)
        runs[co.label]["info"] = r.run(co, "pack", "info --verify", ["info", "z.pack", "--verify"],
                                       cwd)
    for label, out, args in PACK_VARIANTS:
        item = f"{out} ({label})"
        fail = failed_item("pack", item, {k: v[out] for k, v in runs.items()})
        items.append(fail or compare_dirs("pack", item, r.side(old, "pack", out),
                                          r.side(new, "pack", out)))
    info = {k: v["info"] for k, v in runs.items()}
    item = "info z.pack --verify (stdout)"
    same = info["old"].stdout == info["new"].stdout
    items.append(failed_item("pack", item, info) or Item(
        "pack", item, same, "identical" if same else "DIFFERS: " + " vs ".join(
            str(run.log.with_suffix(".out")) for run in info.values())))
    return items


def produce_scenarios(r: Runner, old: Checkout, new: Checkout) -> list[Item]:
    items = []
    for name in SCENARIOS:
        runs = {}
        for co in (old, new):
            cwd = r.fresh(co, "scenario", name)
            runs[co.label] = r.run(co, "scenario", name,
                                   ["scenario", name, "--quick", "--out", "out", "--cache", "cache",
                                    "--no-pace"], cwd)
        out_old = r.side(old, "scenario", name, "out")
        out_new = r.side(new, "scenario", name, "out")
        item = compare_results("scenario", f"{name}.json", out_old / f"{name}.json",
                               out_new / f"{name}.json")
        if runs["old"].rc != runs["new"].rc:  # a failed check exits 1: must match too
            item = Item("scenario", item.item, False,
                        f"DIFFERS: exit {runs['old'].rc} vs {runs['new'].rc}; {item.result}",
                        item.details)
        items.append(item)
        frames = sorted({p.name for d in (out_old, out_new) for pat in SCENARIO_FRAMES
                         for p in d.glob(pat)})
        items += [compare_images("scenario", f, out_old / f, out_new / f) for f in frames]
    return items


def streamed_bands(stdout: str) -> int | None:
    """How many frames the demo's streamed_view.png stacks (from its printed frame list)."""
    m = re.search(r"streamed view frames \[([\d, ]+)\]", stdout)
    return len(m.group(1).split(",")) if m else None


def produce_demo(r: Runner, old: Checkout, new: Checkout) -> list[Item]:
    runs = {}
    for co in (old, new):
        cwd = r.fresh(co, "demo")
        runs[co.label] = r.run(co, "demo", "demo", ["demo", "--workdir", "demo", *DEMO_ARGS], cwd)
    fail = failed_item("demo", "demo", runs)
    if fail:
        return [fail]
    a, b = r.side(old, "demo", "demo"), r.side(new, "demo", "demo")
    items = [compare_images("demo", "painting.tif", a / "painting.tif", b / "painting.tif"),
             compare_dirs("demo", "painting.pack", a / "painting.pack", b / "painting.pack"),
             compare_images("demo", "preview.png", a / "preview.png", b / "preview.png")]
    # streamed_view.png stacks frame 0, frame 2 and the first sharp frame of a loop paced at
    # 90 Hz whose loader thread delivers tiles as they are read: how many arrived by frame 2,
    # and so the sharp frame's number, vary between two runs of the same build. The sharp
    # frame (the last band) must equal the plain mip texture and is compared exactly.
    bands = [streamed_bands(runs[k].stdout) for k in ("old", "new")]
    if None in bands or not all((d / "streamed_view.png").is_file() for d in (a, b)):
        items.append(compare_images("demo", "streamed_view.png", a / "streamed_view.png",
                                    b / "streamed_view.png"))
    else:
        rows = [read_image(p)[0].shape[0] // n for p, n in
                ((a / "streamed_view.png", bands[0]), (b / "streamed_view.png", bands[1]))]
        if rows[0] != rows[1]:
            items.append(Item("demo", "streamed_view.png", False,
                              f"DIFFERS: view height {rows[0]} vs {rows[1]}"))
        else:
            item = compare_images("demo", "streamed_view.png (sharp frame)",
                                  a / "streamed_view.png", b / "streamed_view.png",
                                  rows=slice(-rows[0], None))
            item.details["frames_shown"] = bands
            items.append(item)
    items.append(compare_images("demo", "cornell.png", a / "cornell.png", b / "cornell.png"))
    return items


def produce_renders(r: Runner, old: Checkout, new: Checkout) -> list[Item]:
    runs = {co.label: {} for co in (old, new)}
    for co in (old, new):
        cwd = r.fresh(co, "render")
        for out, args in RENDERS:
            runs[co.label][out] = r.run(co, "render", out, ["render", *args, *RENDER_COMMON,
                                                            "-o", out], cwd)
    items = []
    for out, args in RENDERS:
        item = f"{out}: {' '.join(args)}"
        fail = failed_item("render", item, {k: v[out] for k, v in runs.items()})
        items.append(fail or compare_images("render", item, r.side(old, "render", out),
                                            r.side(new, "render", out)))
    return items


PRODUCERS = [("pack", produce_pack), ("scenario", produce_scenarios), ("demo", produce_demo),
             ("render", produce_renders)]


# ----------------------------------------------------------------------------- speed

def pace_figures(out: Path) -> dict:
    p = json.loads((out / "views_pace.json").read_text())["pace"]
    return {k: v for k, v in p.items() if k.endswith("_ms") or k == "stage_ms_sum"}


def loader_figures(out: Path) -> dict:
    d = json.loads((out / "loader.json").read_text())
    figs = {}
    for codec, c in d.get("loading", {}).items():
        for row in c["rows"]:
            figs[f"{codec} {row['config']} s"] = row["seconds"]
        figs[f"{codec} direct s"] = c["direct_seconds"]
        figs[f"{codec} physical s {CONTROL}"] = c["physical_seconds"]
    for row in d.get("sampling", {}).get("rows", []):
        name = f"sampling {row['pattern']} {row['filter']} {row['threads']}t"
        figs[f"{name} VT ns"] = 1e9 / row["vt_samples_per_s"]
        figs[f"{name} plain ns"] = 1e9 / row["plain_samples_per_s"]
    return figs


def photon_figures(out: Path) -> dict:
    d = json.loads((out / "results.json").read_text())
    figs = {}
    for scene, s in d.items():
        if not (isinstance(s, dict) and "table1" in s):
            continue
        for table in ("table1", "table2", "table3", "table4", "table5"):
            for row in s.get(table, []):
                for k, v in row.items():
                    # Table 2's heap_ms is Table 1's hash_ms, the same measurement.
                    if k.endswith("_ms") and not (table == "table2" and k == "heap_ms"):
                        figs[f"{scene} {table} {row['side']}^2 r{row['r']:g} {k[:-3]}"] = v
    return figs


FIGURES = {"pace": pace_figures, "loader": loader_figures, "photon": photon_figures}


def run_speed(r: Runner, old: Checkout, new: Checkout, pairs: int, full: bool,
              share_cache: bool) -> tuple[dict, bool]:
    """Alternates old / new `pairs` times per benchmark; per headline figure the median of
    each side and the new/old ratio of each pair. Returns (results, all runs succeeded).
    The first loader run also renders and packs the painting into its cache: that shows in
    its wall time, not in its figures."""
    settings = BENCH_FULL if full else BENCH_SHORT
    # bench loader keeps its rendered painting and packs in --cache; shared only when the
    # pack check found both checkouts writing identical packs.
    caches = {co.label: r.work / ("speed-cache" if share_cache else f"{co.label}/speed-cache")
              for co in (old, new)}
    for d in set(caches.values()):
        if d.exists():
            shutil.rmtree(d)
    progress(f"speed: {pairs} pair(s); loader cache {'shared' if share_cache else 'per checkout'}")
    for name, args in settings.items():
        progress(f"speed: {name}: gigascroll {' '.join(args)}")
    results, ok = {}, True
    for name, args in settings.items():
        figs = {"old": [None] * pairs, "new": [None] * pairs}  # per pair; None: failed
        walls = {"old": [], "new": []}
        loads = {"old": [], "new": []}  # other jobs on the machine skew single pairs
        for i in range(pairs):
            for co in (old, new):
                cwd = r.fresh(co, "speed", name, f"run{i}")
                extra = ["--out", "out"]
                if name == "loader":
                    extra += ["--cache", os.path.relpath(caches[co.label], cwd)]
                loads[co.label].append(round(os.getloadavg()[0], 1))
                run = r.run(co, "speed", f"{name} run {i + 1}", [*args, *extra], cwd)
                walls[co.label].append(run.seconds)
                if run.rc != 0:
                    ok = False
                    continue
                try:
                    figs[co.label][i] = FIGURES[name](cwd / "out")
                except (OSError, KeyError, ValueError) as e:
                    progress(f"speed: {name} ({co.label}): cannot read its results: {e}")
                    ok = False
        rows = {}
        keys = dict.fromkeys(k for f in figs["old"] + figs["new"] if f for k in f)
        for k in keys:
            o = [f[k] for f in figs["old"] if f and k in f]
            n = [f[k] for f in figs["new"] if f and k in f]
            ratios = [b[k] / a[k] for a, b in zip(figs["old"], figs["new"])
                      if a and b and k in a and k in b and a[k]]
            rows[k] = {"old": o, "new": n, "ratios": ratios,
                       "old_median": statistics.median(o) if o else None,
                       "new_median": statistics.median(n) if n else None,
                       "median_ratio": statistics.median(ratios) if ratios else None}
        medians = [x["median_ratio"] for k, x in rows.items()
                   if x["median_ratio"] and CONTROL not in k]
        geo = float(np.exp(np.mean(np.log(medians)))) if medians else None
        results[name] = {"command": ["gigascroll", *args], "wall_seconds": walls,
                         "load_average_before": loads, "figures": rows,
                         "geometric_mean_ratio": geo}
    return results, ok


# ----------------------------------------------------------------------------- report

def markdown(items: list[Item]) -> str:
    lines = ["| producer | item | result |", "|---|---|---|"]
    for it in items:
        lines.append(f"| {it.producer} | {it.item} | {it.result} |")
    return "\n".join(lines)


def num(v) -> str:
    return "-" if v is None else f"{v:.4g}"


def speed_markdown(speed: dict) -> str:
    lines = []
    for name, s in speed.items():
        geo = s["geometric_mean_ratio"]
        lines += ["", f"### {' '.join(s['command'])}", "",
                  f"geometric mean of the median new/old ratios (controls left out): "
                  f"{'-' if geo is None else f'{geo:.3f}'}; wall seconds per run: old "
                  f"{[round(x) for x in s['wall_seconds']['old']]}, new "
                  f"{[round(x) for x in s['wall_seconds']['new']]}; 1-minute load average "
                  f"before each run: old {s['load_average_before']['old']}, new "
                  f"{s['load_average_before']['new']} ({os.cpu_count()} cores)", ""]
        load = max(s["load_average_before"]["old"] + s["load_average_before"]["new"], default=0)
        if load > (os.cpu_count() or 1):
            lines += [f"WARNING: load average up to {load} on {os.cpu_count()} cores: other jobs "
                      f"shared the CPU, so these ratios say more about them than about the code; "
                      f"rerun with more --pairs on a quieter machine.", ""]
        lines += ["| figure | old (median) | new (median) | new/old (median) | per pair |",
                  "|---|---|---|---|---|"]
        for k, x in s["figures"].items():
            lines.append(f"| {k} | {num(x['old_median'])} | {num(x['new_median'])} | "
                         f"{num(x['median_ratio'])} | "
                         f"{', '.join(f'{q:.3f}' for q in x['ratios'])} |")
    return "\n".join(lines)


def step_times(steps: list[dict]) -> str:
    totals: dict = {}
    for s in steps:
        t = totals.setdefault(s["producer"], {"old": 0.0, "new": 0.0})
        t[s["side"]] += s["seconds"]
    lines = ["| producer | old s | new s |", "|---|---|---|"]
    lines += [f"| {p} | {t['old']:.1f} | {t['new']:.1f} |" for p, t in totals.items()]
    return "\n".join(lines)


def environments(old: Checkout, new: Checkout) -> dict:
    """Installed package versions that differ between the two venvs (they can explain a
    difference in, say, a matplotlib PNG)."""
    code = ("import importlib.metadata as m, json; print(json.dumps({d.metadata['Name'].lower(): "
            "d.version for d in m.distributions()}))")
    versions = []
    for co in (old, new):
        p = subprocess.run([str(co.root / ".venv" / "bin" / "python"), "-c", code],
                           capture_output=True, text=True, env=clean_env())
        versions.append(json.loads(p.stdout) if p.returncode == 0 else {})
    a, b = versions
    return {k: [a.get(k), b.get(k)] for k in sorted(set(a) | set(b))
            if a.get(k) != b.get(k) and k != "gigascroll"}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="git revision or built checkout directory")
    ap.add_argument("--new", default=str(ROOT),
                    help="git revision or built checkout directory (default: this checkout)")
    ap.add_argument("--work", default=str(ROOT / "build" / "compare"),
                    help="worktrees, outputs and compare.json (default: build/compare here)")
    ap.add_argument("--speed", action="store_true", help="also compare benchmark timings")
    ap.add_argument("--pairs", type=int, default=3, help="old/new run pairs per benchmark (3)")
    ap.add_argument("--full", action="store_true",
                    help="benchmarks at their own default settings (long)")
    args = ap.parse_args(argv)
    if args.pairs < 1:
        ap.error("--pairs must be >= 1")
    work = Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    try:
        # Both are checked before either is built.
        where = {k: locate(k, spec) for k, spec in (("old", args.old), ("new", args.new))}
        old = prepare("old", args.old, where["old"], work)
        new = prepare("new", args.new, where["new"], work)
    except SetupError as e:
        print(f"compare_outputs: error: {e}", file=sys.stderr)
        return 2
    for co in (old, new):
        progress(f"{co.label}: {co.root} at {co.commit[:12] or '(not a git checkout)'}"
                 + (" with uncommitted changes" if co.dirty else ""))
    r = Runner(work)
    items: list[Item] = []
    timings = {}
    for name, produce in PRODUCERS:
        t0 = time.perf_counter()
        items += produce(r, old, new)
        timings[name] = round(time.perf_counter() - t0, 1)
    identical = all(it.identical for it in items)
    summary = {
        "old": {"spec": old.spec, "root": str(old.root), "commit": old.commit, "dirty": old.dirty},
        "new": {"spec": new.spec, "root": str(new.root), "commit": new.commit, "dirty": new.dirty},
        "package_versions_differing": environments(old, new),
        "identical": identical,
        "items": [vars(it) for it in items],
        "producer_seconds": timings,
        "steps": r.steps,
    }
    print("\n" + markdown(items))
    print(f"\n{sum(it.identical for it in items)} of {len(items)} identical. "
          f"Seconds per producer (both sides): "
          + ", ".join(f"{k} {v:.0f}" for k, v in timings.items()) + "\n")
    print(step_times(r.steps))
    versions = summary["package_versions_differing"]
    if versions:
        shown = [f"{k} {a} / {b}" for k, (a, b) in versions.items() if k in OUTPUT_PACKAGES]
        others = len(versions) - len(shown)
        print("\nPackages differing between the two venvs (old / new): "
              + ", ".join(shown + ([f"{others} others (see compare.json)"] if others else [])))
    speed_ok = True
    if args.speed:
        share = all(it.identical for it in items if it.producer == "pack")
        summary["speed"], speed_ok = run_speed(r, old, new, args.pairs, args.full, share)
        summary["steps"] = r.steps
        print(speed_markdown(summary["speed"]))
    (work / "compare.json").write_text(json.dumps(summary, indent=1))
    print(f"\nwrote {work / 'compare.json'}")
    print("all outputs identical" if identical else "OUTPUTS DIFFER")
    return 0 if identical and speed_ok else 1


if __name__ == "__main__":
    sys.exit(main())

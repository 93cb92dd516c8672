"""The light's one knob (gallery/quality.py; `--quality`, `--light-budget`): the rule's
properties against what it must be (scale-free, ordered levels, budgets that pick finer steps
only when larger), and bad values of the options in every command that has them: exit 2 with
one line, nothing written. Each CLI case runs in a forked child (fuzz_support.Worker)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

import gigascroll as g
from gigascroll.gallery.quality import (QUALITY_LEVELS, STEPS, LightSettings, apply_settings, still_spp,
                                        light_settings, predicted_seconds, room_measures)
from gigascroll.room.spec import RoomSpec, Surface

from gallery_checks import box_room, example_room_files

HOSTILE_BUDGETS = ["nan", "inf", "-inf", "-1", "0", "1e308", "1e-320", "x", ""]


def scaled(spec: RoomSpec, s: float) -> RoomSpec:
    """The room with every length times s."""
    surfaces = [Surface(x.name, np.asarray(x.vertices) * s, x.triangles, x.albedo, x.emission)
                for x in spec.surfaces]
    slots = [replace(p, origin=tuple(np.asarray(p.origin) * s), width_m=p.width_m * s,
                     height_m=p.height_m * s) for p in spec.paintings]
    return RoomSpec(spec.name, surfaces, slots)


def test_the_rule_is_scale_free():
    """A room scaled by s (its lights too) gets the same photons, samples and gathers, and a
    spacing scaled by s: the same light field at another size gets the same relative error."""
    room = box_room()
    for level in QUALITY_LEVELS:
        a, b = light_settings(room, level), light_settings(scaled(room, 7.5), level)
        assert (a.photons, a.light_samples, a.final_gather, a.gather_stride, a.spp) == \
               (b.photons, b.light_samples, b.final_gather, b.gather_stride, b.spp)
        assert math.isclose(b.spacing, 7.5 * a.spacing, rel_tol=1e-9)


def test_the_levels_are_ordered_and_read_the_room():
    """draft <= preview <= final in every setting; the spacing is the diagonal's fraction; a
    room with more surface in the same bounds gets more photons."""
    room = box_room()
    d, p, f = (light_settings(room, q) for q in QUALITY_LEVELS)
    for a, b in ((d, p), (p, f)):
        assert a.photons <= b.photons and a.spacing >= b.spacing and a.light_samples <= b.light_samples
        assert a.final_gather <= b.final_gather and a.spp <= b.spp
    diag = math.dist((-2, 0, -2), (2, 3, 2))  # box_room's bounds
    assert math.isclose(f.spacing, diag / STEPS[4].diagonal_over, rel_tol=1e-6)
    extra = [Surface(f"partition{i}", np.array([[-1.9, 0, z], [1.9, 0, z], [1.9, 2.9, z], [-1.9, 2.9, z]]),
                     np.array([[0, 1, 2], [0, 2, 3]]), (0.5, 0.5, 0.5)) for i, z in enumerate(np.linspace(-1.8, 1.8, 8))]
    busy = RoomSpec("busy", room.surfaces + extra, room.paintings)
    assert room_measures(busy).area > 2 * room_measures(room).area
    assert light_settings(busy, "final").photons > f.photons


def test_budgets_pick_finer_steps_only_when_larger():
    room = box_room()
    budgets = [1e-4, 1e-3, 0.01, 0.03, 0.1, 0.3, 1, 3, 10, 100]
    chosen = [light_settings(room, budget=b) for b in budgets]
    steps = [c.step for c in chosen]
    assert steps == sorted(steps) and steps[0] == 0 and steps[-1] == len(STEPS) - 1
    m = room_measures(room)
    for b, c in zip(budgets, chosen):
        assert c.level == "budget" and c.budget_s == b
        assert c.step == 0 or predicted_seconds(c, m) <= b


@pytest.mark.parametrize("bad", [dict(quality="best"), dict(quality=3), dict(budget=-1.0),
                                 dict(budget=float("nan")), dict(budget=float("inf")), dict(budget=True),
                                 dict(budget="1"), dict(budget=1e9), dict(quality="draft", budget=1.0)])
def test_bad_levels_and_budgets_are_value_errors(bad):
    with pytest.raises(ValueError):
        light_settings(box_room(), **bad)


def test_rooms_without_extent_and_bad_overrides_are_value_errors(tmp_path):
    with pytest.raises(ValueError):
        light_settings("scroll")
    with pytest.raises(ValueError):
        light_settings(RoomSpec("empty"))
    flat = Surface("dot", np.zeros((3, 3)), np.array([[0, 1, 2]]), (0.5, 0.5, 0.5), (1, 1, 1))
    with pytest.raises(ValueError, match="extent"):
        light_settings(RoomSpec("dot", [flat]))
    s = light_settings(box_room(), "draft")
    with pytest.raises(ValueError, match="unknown"):
        apply_settings(None, s, radius=3)
    with pytest.raises(ValueError, match="LightSettings"):
        apply_settings(None, {"photons": 3})
    assert isinstance(s, LightSettings)


# ---------------------------------------------------------------------------- the commands

@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return example_room_files(tmp_path_factory.mktemp("quality"))


def commands(d, out):
    """argv of each command that lights a room, up to where --quality / --light-budget go."""
    room, pack = str(d / "room.glb"), str(d / "ex.pack")
    return {"render": ["render", "--room", room, "--pack", pack, "-o", str(out) + ".png", "--width", "12",
                       "--height", "9", "--threads", "1"],
            "gallery": ["gallery", pack, "--room", room, "--eye", "16x16", "--seconds", "0.1", "--no-video",
                        "--out", str(out)],
            "view": ["view", pack, "--room", room],
            "serve": ["serve", pack, "--room", room, "--port", "0", "--cache-dir", str(out)],
            "exhibit": ["exhibit", "build", str(d / "missing.toml"), "-o", str(out)]}


@pytest.mark.parametrize("command", ["render", "gallery", "view", "serve", "exhibit"])
@pytest.mark.parametrize("option", [["--quality", "best"], ["--quality", ""], ["--light-budget", "nan"],
                                    ["--light-budget", "-1"], ["--light-budget", "0"], ["--light-budget", "inf"],
                                    ["--light-budget", "x"], ["--quality", "draft", "--light-budget", "1"]])
def test_bad_values_exit_2_with_one_line(fork_worker, files, tmp_path, command, option):
    out = tmp_path / "out"
    argv = commands(files, out)[command] + option
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=60)
    assert o.code == 2 and cli_message_ok(o) is None, o.describe()
    assert "--quality" in o.stderr or "--light-budget" in o.stderr, o.stderr
    assert not out.exists() and not (tmp_path / "out.png").exists()


@pytest.mark.parametrize("option", [["--quality", "draft"], ["--light-budget", "0.01"]])
def test_the_knob_reaches_the_still(fork_worker, files, tmp_path, option):
    """render --room with the knob: exit 0, the chosen settings printed, and the photons the
    rule chose emitted."""
    argv = commands(files, tmp_path / "out")["render"] + option
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    assert o.code == 0, o.describe()
    s = light_settings(load_example(files), *(("draft",) if option[0] == "--quality" else ()),
                       **({"budget": 0.01} if option[0] == "--light-budget" else {}))
    assert f"({s.photons} emitted" in o.stdout and s.level in o.stdout, o.stdout


def test_the_still_takes_the_levels_rays_per_pixel(fork_worker, files, tmp_path):
    """render --room at final without --spp: the level's rays a pixel (49), said on the output."""
    argv = commands(files, tmp_path / "out")["render"] + ["--quality", "final"]
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    assert o.code == 0, o.describe()
    assert light_settings(load_example(files), "final").spp == 49
    assert "12x9, 49 spp, lighting" in o.stdout, o.stdout


@pytest.mark.parametrize("spp", [1, 4, 9, 49, 81])
def test_the_levels_rays_per_pixel_are_capped_at_2_26_samples(spp):
    """still_spp against brute force: the largest square k^2 <= the level's with width x height x
    k^2 <= 2^26, at least 1."""
    for w, h in [(1, 1), (12, 9), (1280, 720), (1600, 1000), (1920, 1080), (4096, 4096), (8192, 8192), (3, 7)]:
        best = max([k * k for k in range(1, 10) if k * k <= spp and w * h * k * k <= 1 << 26], default=1)
        assert still_spp(spp, w, h) == best, (spp, w, h)


@fuzz_settings(200)
@given(k=st.integers(1, 12), w=st.integers(1, 1 << 20), h=st.integers(1, 1 << 20))
def test_random_still_sizes_keep_within_2_26_samples(k, w, h):
    """Any size, huge ones included: a square of at least 1, at most the level's, within 2^26
    samples unless even one ray a pixel is over, and no larger square would fit."""
    count_case("light quality")
    s = still_spp(k * k, w, h)
    r = math.isqrt(s)
    assert r * r == s and 1 <= r <= k
    assert w * h * s <= 1 << 26 or s == 1
    assert r == k or w * h * (r + 1) ** 2 > 1 << 26


def load_example(files):
    from gigascroll.room.files import load_room

    return load_room(files / "room.glb", g.TilePack(files / "ex.pack"))


@fuzz_settings(10)
@given(data=st.data())
def test_random_knob_values(fork_worker, files, tmp_path_factory, data):
    """Random values of the two options (and both at once) in render --room: exit 0 or one line."""
    count_case("light quality")
    out = tmp_path_factory.mktemp("knob") / "out"
    option = data.draw(st.sampled_from([["--quality", q] for q in (*QUALITY_LEVELS[:2], "FINAL", "💥")]
                                       + [["--light-budget", b] for b in HOSTILE_BUDGETS + ["0.001", "0.02"]]
                                       + [["--quality", "draft", "--light-budget", "0.5"]]))
    argv = commands(files, out)["render"] + ["--photons", "500"] + option
    o = fork_worker.run({"kind": "cli", "argv": argv}, timeout=120)
    problem = cli_message_ok(o)
    assert problem is None, f"{problem}: {argv}\n{o.describe()}"

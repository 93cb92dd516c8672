"""Where the commands write when the user names no output, and what they say about it:
next to the pack (never `build/...` under whatever directory the command runs from), the path
printed; `gallery` takes one pack and its usage says so; the walk's two frame rates are
labelled, in the console, the report and results.json, and equal to what the per-frame
records give when recomputed here."""

import argparse
import json
import os
import statistics
from pathlib import Path

import pytest

from gigascroll import cli
from gigascroll.commands import gallery as gallery_cmd
from gigascroll.commands.view import default_screenshot, screenshot_pattern
from gigascroll.walk.frame_rates import FPS_MEANING
from gigascroll.outputs import beside


def _subparsers(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices
    return {}


def test_no_user_command_defaults_into_build():
    # Benchmarks (`bench ...`) are developer tools run from the repository; every other
    # command's default output, work or cache directory must not be build/ under the cwd.
    parser = cli.build_parser()
    for name, sub in _subparsers(parser).items():
        if name == "bench":
            continue
        for action in sub._actions:
            if isinstance(action.default, str):
                assert not action.default.replace("\\", "/").startswith("build"), \
                    f"{name} {action.option_strings or action.dest}: {action.default}"


def test_beside_names_the_output_after_its_anchor(tmp_path):
    assert beside(tmp_path / "shows" / "a.pack", "walk") == tmp_path / "shows" / "a-walk"
    assert beside(str(tmp_path / "b.pack") + "/", "walk") == tmp_path / "b-walk"
    assert beside(tmp_path / "plain", "x") == tmp_path / "plain-x"
    assert beside("c.pack", "walk") == Path(os.path.abspath("c-walk"))  # absolute: printable


def test_view_screenshots_default_next_to_the_pack(tmp_path):
    pack = tmp_path / "odd{name}.pack"
    pattern = screenshot_pattern(default_screenshot(str(pack)))
    assert pattern.format(n=7) == str(tmp_path / "odd{name}-view-7.png")


def test_view_default_screenshot_does_not_hide_the_real_error(gigascroll_cli, tmp_path):
    # The default pattern lies beside the pack: a missing directory is the pack's problem
    # (reported later, as without the default), not a --screenshot the user never gave.
    import subprocess
    import sys
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    r = subprocess.run([sys.executable, "-m", "gigascroll", "view", str(tmp_path / "no" / "p.pack")],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 2 and "--screenshot" not in r.stderr, r.stderr


def test_gallery_usage_says_one_pack(gigascroll_cli, tmp_path):
    r = gigascroll_cli("gallery", "--help")
    assert r.returncode == 0
    usage = " ".join(r.stdout.split("\n\n")[0].split())
    assert "[PACK]" in usage and "PACK ..." not in usage
    r = gigascroll_cli("gallery", tmp_path / "a.pack", tmp_path / "b.pack", "--eye", "16x16")
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2 and len(lines) == 1 and "b.pack" in lines[0], r.stderr
    assert not any(tmp_path.iterdir())


def test_builtin_painting_goes_to_the_user_cache(monkeypatch, tmp_path, capsys):
    cache, cwd = tmp_path / "cache", tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
    monkeypatch.setattr(gallery_cmd, "BUILTIN_PAINTING", (260, 130))
    pack = gallery_cmd.builtin_pack()
    assert os.path.samefile(pack.path, cache / "gigascroll" / "gallery-painting.pack")
    assert (pack.paintings[0].width, pack.paintings[0].height) == (260, 130)
    assert str(cache / "gigascroll" / "gallery-painting.pack") in capsys.readouterr().out
    assert not any(cwd.iterdir())
    again = gallery_cmd.builtin_pack()  # packed once: the second call opens it
    assert capsys.readouterr().out == "" and again.path == pack.path


@pytest.fixture(scope="module")
def walk_next_to_pack(tmp_path_factory, small_scroll_pack):
    """`gigascroll gallery PACK` without --out, run from another directory."""
    import shutil
    import subprocess
    import sys
    home = tmp_path_factory.mktemp("shows")
    pack = home / "mine.pack"
    shutil.copytree(small_scroll_pack.path, pack)
    cwd = tmp_path_factory.mktemp("elsewhere")
    r = subprocess.run([sys.executable, "-m", "gigascroll", "gallery", str(pack), "--eye", "32x34",
                        "--seconds", "0.12", "--photons", "3000", "--no-video"],
                       capture_output=True, text=True, cwd=cwd, timeout=300)
    return r, home, cwd


def test_gallery_output_lands_next_to_the_pack(walk_next_to_pack):
    r, home, cwd = walk_next_to_pack
    assert r.returncode == 0, r.stderr
    out = home / "mine-walk"
    assert (out / "results.json").is_file() and (out / "report.md").is_file()
    assert not any(cwd.iterdir()), list(cwd.iterdir())
    assert f"wrote {out}/" in r.stdout


def test_walk_frame_rates_are_labelled(walk_next_to_pack):
    r, home, _ = walk_next_to_pack
    res = json.loads((home / "mine-walk" / "results.json").read_text())
    s, frames = res["summary"], res["frames"]
    # The rates against the per-frame records.
    times = [f["time_s"] for f in frames]
    assert s["fps"] == pytest.approx((len(frames) - 1) / (times[-1] - times[0]))
    assert s["fps_from_frame_time"] == pytest.approx(
        1e3 / statistics.mean(f["total_ms"] for f in frames))
    assert s["oracle_ms"] == pytest.approx(statistics.mean(f["oracle_ms"] for f in frames))
    assert s["fps_meaning"] == FPS_MEANING
    line = next(ln for ln in r.stdout.splitlines() if " frames at 32x34 per eye" in ln)
    loop = f"{s['fps_from_frame_time']:.2f} fps in the frame loop alone"
    wall = f"{s['fps']:.2f} fps of wall clock with the oracle and recording"
    assert loop in line and wall in line
    report = (home / "mine-walk" / "report.md").read_text()
    assert loop in report and wall in report and "oracle comparison" in report

"""The display-comparison scripts beside the walk benchmark (bench/walk/): frame_diff's image
difference against a per-pixel loop, its verdicts on saves that agree or differ, and bad input
(missing or foreign files, bad sizes and counts) as one line and exit 2 for all three scripts."""

import importlib.util
import pathlib
import subprocess
import sys

import numpy as np
import pytest

WALK = pathlib.Path(__file__).resolve().parents[2] / "bench" / "walk"


def _frame_diff():
    spec = importlib.util.spec_from_file_location("frame_diff", WALK / "frame_diff.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(script, *args):
    out = subprocess.run([sys.executable, str(WALK / script), *map(str, args)],
                         capture_output=True, text=True, timeout=120)
    return out.returncode, out.stdout, out.stderr.strip()


def test_image_difference_matches_a_per_pixel_loop():
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 2, (7, 9, 3)).astype(np.float32)
    b = a.copy()
    b[rng.uniform(size=(7, 9)) < 0.4] *= np.float32(1 + 3e-6)
    b[2, 3, 1] = a[2, 3, 1] + 0.25
    a[0, 0] = [0, 0, 0]
    b[0, 0] = [5e-4, 0, 0]  # below the floor: absolute against 1e-3
    rel, differ = _frame_diff().image_difference(a, b)
    worst, changed = 0.0, 0
    for y in range(7):
        for x in range(9):
            changed += any(a[y, x, c] != b[y, x, c] for c in range(3))
            for c in range(3):
                p, q = float(a[y, x, c]), float(b[y, x, c])
                worst = max(worst, abs(p - q) / max(abs(p), abs(q), float(np.float32(1e-3))))
    assert rel == pytest.approx(worst, rel=1e-12)
    assert differ == changed / 63
    assert _frame_diff().image_difference(a, a) == (0.0, 0.0)


def _save(path, poses=2, shift=0.0, level=0):
    rng = np.random.default_rng(5)
    left = rng.uniform(0, 1, (poses, 4, 5, 3)).astype(np.float32)
    np.savez(path, left=left + np.float32(shift), right=left, sources=np.zeros((poses, 20), np.int32),
             levels=np.full((poses, 2, 20), level, np.float32), hits=np.zeros((poses, 2, 60), np.float32))
    return path


def test_frame_diff_verdicts(tmp_path):
    a = _save(tmp_path / "a.npz")
    rc, out, _ = _run("frame_diff.py", a, _save(tmp_path / "b.npz", shift=1e-6))
    lines = out.splitlines()
    assert rc == 0 and len(lines) == 2
    for line in lines:  # a shift of 1e-6 on values in [0, 1): every pixel, at most 1e-6 / 1e-3 relative
        assert "(100% of pixels differ), right 0 rel (0% of pixels differ)" in line
        assert 0 < float(line.split("left ")[1].split(" rel")[0]) <= 1.01e-3
        assert line.endswith("sources equal, levels equal, hits equal")
    rc, out, _ = _run("frame_diff.py", a, a)
    assert rc == 0 and "left 0 rel (0% of pixels differ)" in out
    rc, out, _ = _run("frame_diff.py", a, _save(tmp_path / "c.npz", level=1))
    assert rc == 1 and "levels DIFFER" in out


@pytest.mark.parametrize("case", ["missing", "not_npz", "other_shape", "lacks_hits"])
def test_frame_diff_bad_input_exits_2(tmp_path, case):
    a = _save(tmp_path / "a.npz")
    b = tmp_path / "b.npz"
    if case == "not_npz":
        b.write_bytes(b"\x00garbage" * 10)
    elif case == "other_shape":
        _save(b, poses=3)
    elif case == "lacks_hits":
        np.savez(b, left=np.zeros(1), right=np.zeros(1))
    rc, out, err = _run("frame_diff.py", a, b)
    assert rc == 2 and err.startswith("frame_diff: ") and "\n" not in err and out == ""


@pytest.mark.parametrize("args", [["--alternations", "0"], ["--rounds", "-1"], ["--eye", "0x480"],
                                  ["--eye", "450by480"], []])
def test_alternate_bad_input_exits_2(tmp_path, args):
    rc, _, err = _run("alternate.py", tmp_path / "no_old.so", tmp_path / "no_new.so", *args)
    assert rc == 2 and err.startswith("alternate.py: ") and "\n" not in err


@pytest.mark.parametrize("args", [["0x0"], ["wide"], ["450x480", "--save", "/nonexistent/dir/x.npz"]])
def test_frame_hashes_bad_input_exits_2(args):
    rc, _, err = _run("frame_hashes.py", *args)
    assert rc == 2 and err.startswith("frame_hashes.py: ") and "\n" not in err

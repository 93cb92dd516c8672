"""Outputs and inputs in shapes the first hardening tests did not try: an export written into
the pack it reads (`-o PACK/index.bin --force` replaced the pack's own index and exited 0), a
sharded build whose scheduler is never reached (it left an empty OUT.shards/ behind), and a
camera path whose numbers are strings or booleans (numpy read "6" as 6.0: a wrong walk
instead of an error)."""

from __future__ import annotations

import hashlib
import json
import os
import socket
import subprocess
import sys

import pytest

from gigascroll import build_pack
from gigascroll.experiments import pattern_image
from gigascroll.export import export_pack
from gigascroll.outputs import refuse_input
from gigascroll.views import CameraPath


def _digests(folder) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def pack_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("audit-outputs")
    build_pack(pattern_image(200, 90), root / "p.pack", tile_size=32, border=2)
    return root / "p.pack"


@pytest.mark.parametrize("fmt, name", [("tiff", "index.bin"), ("tiff", "manifest.json"),
                                       ("tiff", "new.tif"), ("iiif", "sub"), ("dzi", "deep")])
def test_export_never_writes_into_its_pack(pack_dir, tmp_path, fmt, name):
    before = _digests(pack_dir)
    link = tmp_path / "link.pack"
    link.symlink_to(pack_dir, target_is_directory=True)
    for source, out in ((pack_dir, pack_dir / name), (link, pack_dir / name),
                        (pack_dir, link / name), (pack_dir, pack_dir / "x" / ".." / name)):
        with pytest.raises(OSError, match="inside the pack being exported"):
            export_pack(source, out, fmt, force=True)
    assert _digests(pack_dir) == before
    # Beside the pack is fine, and reads back the pack's pixels (the export's own tests
    # compare them): here only that it was written.
    assert export_pack(pack_dir, tmp_path / f"ok-{fmt}", fmt).exists()


def test_export_into_its_pack_is_one_line_exit_2(pack_dir):
    before = _digests(pack_dir)
    r = subprocess.run([sys.executable, "-m", "gigascroll", "export", str(pack_dir), "-o",
                        str(pack_dir / "index.bin"), "--format", "tiff", "--force"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "inside the pack being exported" in r.stderr
    assert _digests(pack_dir) == before


@pytest.mark.parametrize("out, source, word", [
    ("a", "a", "is"), ("a/b", "a", "is inside"), ("a", "a/b/c", "holds"),
    ("a/../a/b", "a", "is inside"), ("link/b", "a", "is inside")])
def test_refuse_input_by_name_and_through_links(tmp_path, out, source, word):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "link").symlink_to(tmp_path / "a", target_is_directory=True)
    with pytest.raises(OSError, match=f": {word} the input"):
        refuse_input(tmp_path / out, tmp_path / source, "the input")
    for other in ("ab", "a-b", "c"):  # a shared prefix is not a parent
        assert refuse_input(tmp_path / other, tmp_path / "a") == tmp_path / other


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreached_scheduler_leaves_no_shard_directory(tmp_path):
    pytest.importorskip("dask.distributed")
    from PIL import Image
    import numpy as np
    Image.fromarray(np.zeros((20, 30, 3), np.uint8)).save(tmp_path / "a.png")
    r = subprocess.run([sys.executable, "-m", "gigascroll", "pack", "a.png", "-o", "z.pack",
                        "--scheduler", f"tcp://127.0.0.1:{_closed_port()}", "--timeout", "2"],
                       capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["a.png"]


GOOD = {"fps": 30, "position": [[1, 1.6, 2], [1.1, 1.6, 2]], "forward": [[0, 0, -1]] * 2,
        "up": [[0, 1, 0]] * 2}


@pytest.mark.parametrize("change, message", [
    ({"position": [["1", 1.6, 2], [1.1, 1.6, 2]]}, "not a number"),
    ({"forward": [[0, 0, -1], [0, 0, True]]}, "not a number"),
    ({"up": [[0, 1, 0], [0, None, 0]]}, "not a number"),
    ({"position": [[1, 1.6], [1.1, 1.6, 2]]}, "shape"),
    ({"position": {"0": [1, 1.6, 2]}}, "wrong type"),
    ({"magnifier_target": [[0, 1.5, 0], ["0", 1.5, 0]], "magnifier_normal": [[0, 0, 1]] * 2},
     "not a number"),
])
def test_camera_path_numbers_must_be_numbers(tmp_path, change, message):
    path = tmp_path / "p.json"
    path.write_text(json.dumps({**GOOD, **change}))
    with pytest.raises(ValueError, match=message):
        CameraPath.load(path)
    # The same file with numbers loads, to the values numpy reads from it.
    path.write_text(json.dumps(GOOD))
    p = CameraPath.load(path)
    assert p.position.tolist() == [[1, 1.6, 2], [1.1, 1.6, 2]] and p.fps == 30
    path.write_text(json.dumps({**GOOD, "magnifier_target": [[0, 1.5, 0], [None] * 3],
                                "magnifier_normal": [[0, 0, 1], [None] * 3]}))
    assert CameraPath.load(path).magnifier_target[0].tolist() == [0, 1.5, 0]


SIGTERM_WHILE_WORKERS_START = '''
import asyncio, pathlib, sys
import distributed.nanny
async def slow_start(self):  # the nanny announces itself, then takes its time
    pathlib.Path({marker!r}).touch()
    await asyncio.sleep(120)
distributed.nanny.Nanny.start_unsafe = slow_start
from gigascroll import cli
raise SystemExit(cli.main(["pack", "a.png", "b.png", "-o", "z.pack", "--workers", "2"]))
'''


def test_sigterm_while_dask_workers_start_is_one_line(tmp_path):
    """SIGTERM while the local Dask cluster's workers start: one line and exit 143, not
    distributed's exit hook's AssertionError traceback and 'Task exception was never
    retrieved'."""
    import signal
    import time
    pytest.importorskip("dask.distributed")
    from PIL import Image
    import numpy as np
    for name in ("a.png", "b.png"):
        Image.fromarray(np.zeros((20, 30, 3), np.uint8)).save(tmp_path / name)
    marker = tmp_path / "nanny-starting"
    p = subprocess.Popen([sys.executable, "-c", SIGTERM_WHILE_WORKERS_START.format(marker=str(marker))],
                         cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(1200):
            if marker.exists() or p.poll() is not None:
                break
            time.sleep(0.05)
        assert marker.exists(), p.communicate(timeout=60)
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    lines = [line for line in err.replace("\r", "\n").splitlines() if line.strip()]
    assert p.returncode == 143 and "Traceback" not in err, err[-3000:]
    assert lines[-1] == "gigascroll pack: interrupted (stopped by SIGTERM)", err[-3000:]
    assert not (tmp_path / "z.pack").exists()


@pytest.mark.parametrize("command, words", [("light", "the pack being lit"),
                                             ("gallery", "the pack being walked")])
@pytest.mark.parametrize("out", ["l", ".", "x/../l"])
def test_light_and_gallery_never_write_into_their_pack(pack_dir, out, command, words):
    before = _digests(pack_dir)
    target = os.path.normpath(str(pack_dir / out)) if out == "." else str(pack_dir / out)
    r = subprocess.run([sys.executable, "-m", "gigascroll", command, str(pack_dir), "--room",
                        "scroll", "--out", target], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert words in r.stderr
    assert _digests(pack_dir) == before


def test_view_screenshots_never_go_into_its_pack(pack_dir):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    for shot in ("shot-{n}.png", "../p.pack/a.png"):
        r = subprocess.run([sys.executable, "-m", "gigascroll", "view", str(pack_dir), "--room",
                            "scroll", "--screenshot", str(pack_dir / shot)],
                           capture_output=True, text=True, timeout=120, env=env)
        assert r.returncode == 2 and "inside the pack being viewed" in r.stderr, r.stderr
    for tour in ("tour-{n}.json", "../p.pack/t.json"):  # nor the tours it records
        r = subprocess.run([sys.executable, "-m", "gigascroll", "view", str(pack_dir), "--room",
                            "scroll", "--record-tour", str(pack_dir / tour)],
                           capture_output=True, text=True, timeout=120, env=env)
        assert r.returncode == 2 and "--record-tour" in r.stderr, r.stderr
        assert "inside the pack being viewed" in r.stderr, r.stderr
    # Beside the pack the same pattern passes this check (and meets the missing display).
    r = subprocess.run([sys.executable, "-m", "gigascroll", "view", str(pack_dir), "--room",
                        "scroll", "--screenshot", str(pack_dir.parent / "shot-{n}.png")],
                       capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 2 and "no display" in r.stderr, r.stderr


def test_render_never_writes_into_its_pack(pack_dir, tmp_path):
    before = _digests(pack_dir)
    argv = [sys.executable, "-m", "gigascroll", "render", "--room", "scroll", "--pack", str(pack_dir),
            "--width", "8", "--height", "8", "--lighting", "unlit", "-o"]
    r = subprocess.run(argv + [str(pack_dir / "still.png")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and "inside the pack being rendered" in r.stderr, r.stderr
    assert _digests(pack_dir) == before
    r = subprocess.run(argv + [str(tmp_path / "still.png")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and (tmp_path / "still.png").is_file(), r.stderr

"""Packs on disk (gigascroll.pack.build): replacing a pack with force=True is atomic for a
concurrent reader, SIGTERM / SIGHUP clean up like SIGINT, and a later build removes the
temporary directories of builds whose process is gone (and only those)."""

import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from pack_reference import check_pack_against, noise

from gigascroll import TilePack, build_pack


def test_force_replacement_is_atomic_for_a_reader(tmp_path):
    out = tmp_path / "p"
    images = {"a": noise(40, 60, seed=1), "b": noise(40, 60, seed=2)}
    build_pack(images["a"], out, tile_size=16, border=2, names=["a"])
    seen, failures, stop = [], [], threading.Event()

    def reader():
        # A read that starts in the old pack and outlives the swap sees that pack being
        # deleted (it holds the old directory, no longer the one at the path): such reads are
        # recognised by the directory at the path having changed meanwhile, and retried. What
        # must never happen is a read that begins and ends on one directory and finds it
        # incomplete, or no pack at the path.
        while not stop.is_set():
            try:
                before = os.stat(out).st_ino
            except Exception as e:  # noqa: BLE001 - no pack at the path is the bug
                failures.append(repr(e))
                continue
            try:  # the three files must always be there, together
                names = sorted(os.listdir(out))
                pack = TilePack(out) if names == ["index.bin", "manifest.json",
                                                  "tiles-00000.bin"] else None
                failure = None if pack else f"listing {names}"
            except Exception as e:  # noqa: BLE001 - any failure to open is the bug
                failure = repr(e)
            try:
                swapped = os.stat(out).st_ino != before
            except Exception as e:  # noqa: BLE001
                failures.append(repr(e))
                continue
            if swapped:
                continue
            if failure:
                failures.append(failure)
            else:
                seen.append(pack.paintings[0].name)

    t = threading.Thread(target=reader)
    t.start()
    try:
        for k in range(6):
            name = "ab"[(k + 1) % 2]
            build_pack(images[name], out, tile_size=16, border=2, names=[name], force=True)
    finally:
        stop.set()
        t.join()
    assert not failures, failures[:5]
    assert len(seen) > 0 and set(seen) <= {"a", "b"}
    pack = TilePack(out)
    assert pack.paintings[0].name == "a"  # the 6th build
    check_pack_against(pack, 0, images["a"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p"]  # the old pack is gone


def test_fallback_replacement_keeps_one_pack(tmp_path, monkeypatch):
    # Without RENAME_EXCHANGE (another OS or file system) the old pack is moved aside first.
    from gigascroll import outputs
    monkeypatch.setattr(outputs, "_exchange", lambda a, c: False)
    out = tmp_path / "p"
    build_pack(noise(20, 30, seed=1), out, tile_size=16, border=2)
    img = noise(30, 20, seed=3)
    check_pack_against(build_pack(img, out, tile_size=16, border=2, force=True), 0, img)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p"]


# A child process that builds a big pack slowly (small bands) and reports when it started.
# The child starts from the default dispositions of SIGINT and SIGHUP whatever this process
# inherited (a shell's background job ignores SIGINT, nohup ignores SIGHUP, and a build leaves
# a caller's ignored signal alone by design).
_SLOW_BUILD = """
import signal, sys, time, numpy as np, gigascroll
signal.signal(signal.SIGINT, signal.default_int_handler)
signal.signal(signal.SIGHUP, signal.SIG_IGN if sys.argv[2:] == ["nohup"] else signal.SIG_DFL)
from gigascroll.pack import ArraySource
class Slow(ArraySource):
    def bands(self):
        for i, band in enumerate(super().bands()):
            if i == 1:
                print("started", flush=True)
            time.sleep(0.01)
            yield band
img = np.zeros((4000, 64, 3), np.uint8)
gigascroll.build_pack([Slow(img, "x", band_rows=8)], sys.argv[1], tile_size=16, border=2)
print("finished", flush=True)
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_signal_during_build_cleans_up(tmp_path, sig):
    out = tmp_path / "p"
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_BUILD, str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        assert list(tmp_path.glob("p.tmp-*"))  # the build is under way in its tmp directory
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode != 0
    assert "Interrupt" in err  # BuildInterrupted / KeyboardInterrupt, not a default kill
    assert not any(tmp_path.iterdir()), list(tmp_path.iterdir())


def test_build_under_nohup_ignores_sighup(tmp_path):
    """A caller that ignores SIGHUP (nohup) keeps its choice: the build goes on to a whole pack."""
    out = tmp_path / "p"
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_BUILD, str(out), "nohup"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "started"
        proc.send_signal(signal.SIGHUP)
        rest, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert rest.strip() == "finished"
    check_pack_against(TilePack(out), 0, np.zeros((4000, 64, 3), np.uint8))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p"]


def test_cli_reports_sigterm_with_its_exit_code(tmp_path):
    from gigascroll.pack.build import BuildInterrupted
    e = BuildInterrupted(signal.SIGTERM)
    assert isinstance(e, KeyboardInterrupt) and e.signum == signal.SIGTERM
    assert "SIGTERM" in str(e)


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid  # reaped: no process has it (until reuse, which a short test does not meet)


def test_next_build_removes_leftovers_of_dead_builds_only(tmp_path):
    dead = _dead_pid()
    stale = tmp_path / f"p.tmp-{dead}"
    stale.mkdir()
    (stale / "tiles.bin").write_bytes(b"\0" * 1000)
    stale_old = tmp_path / f"p.tmp-{dead}-old"
    stale_old.mkdir()
    live = tmp_path / f"p.tmp-{os.getppid()}"  # a live process (our parent): its build stays
    live.mkdir()
    other = tmp_path / f"q.tmp-{dead}"  # another output's leftovers: not this build's business
    other.mkdir()
    unrelated = tmp_path / f"p.tmp-{dead}x"
    unrelated.mkdir()
    build_pack(noise(10, 10), tmp_path / "p", tile_size=16, border=2)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(["p", live.name, other.name, unrelated.name])


def test_sigkilled_build_is_cleaned_by_the_next(tmp_path):
    out = tmp_path / "p"
    proc = subprocess.Popen([sys.executable, "-c", _SLOW_BUILD, str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout.readline().strip() == "started"
    proc.kill()
    proc.wait()
    assert len(list(tmp_path.glob("p.tmp-*"))) == 1
    img = noise(12, 9)
    check_pack_against(build_pack(img, out, tile_size=16, border=2), 0, img)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p"]

"""gigascroll.outputs, the one way commands write and replace outputs: which directories may
be replaced (checked against the file tree itself: every file of a refused place is still
there, byte for byte), atomic files on a full disk (a 1 MiB tmpfs where mounting is allowed)
and past a file-size limit (RLIMIT_FSIZE in a child process, always), images read back by
Pillow against the array written, and SIGTERM turned into the cleanup of Ctrl-C."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gigascroll import outputs
from gigascroll.outputs import (MARK, check_output, has_mark, owned_by, protected_reason,
                                replace_dir, write_bytes, write_image, write_mark)


def tree(root: Path) -> dict:
    """Every file under root (not following links) with its bytes: what must stay."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in filenames + [d for d in dirnames if os.path.islink(os.path.join(dirpath, d))]:
            p = Path(dirpath) / name
            out[str(p.relative_to(root))] = (os.readlink(p) if p.is_symlink() else p.read_bytes())
    return out


@pytest.fixture
def nest(tmp_path, monkeypatch):
    """A working directory three levels down, a home beside it, user files everywhere."""
    home = tmp_path / "home"
    cwd = tmp_path / "a" / "b" / "c"
    for d in (home, cwd):
        d.mkdir(parents=True)
    for d in (tmp_path, tmp_path / "a", tmp_path / "a" / "b", cwd, home):
        (d / "precious.txt").write_text(f"user data in {d.name}")
    (cwd / "mine").mkdir()
    (cwd / "mine" / "notes.txt").write_text("not an output")
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(cwd)
    return tmp_path


def refused_places(root: Path) -> list[str]:
    """Paths (relative to the working directory nest()'s makes) that must never be replaced."""
    cwd = root / "a" / "b" / "c"
    for name, target in (("to-parent", ".."), ("to-home", str(root / "home")),
                         ("to-root", "/"), ("to-mine", "mine"), ("to-cwd", ".")):
        os.symlink(target, cwd / name)
    return [".", "..", "../..", "/", str(root / "home"), "~", str(root / "a"), "./", "mine",
            "to-parent", "to-home", "to-root", "to-mine", "to-cwd", "mine/..", "../c"]


def test_refused_places_keep_every_file(nest):
    places = refused_places(nest)
    before = tree(nest)
    for place in places:
        path = os.path.expanduser(place)
        with pytest.raises(OSError, match="refusing"):
            check_output(path, force=True, directory=True, owned=lambda p: False)
        new = nest / "new"
        new.mkdir()
        with pytest.raises(OSError):
            replace_dir(new, path, owned=lambda p: False)
        new.rmdir()
    assert tree(nest) == before
    # protected_reason names the place; an ordinary new or marked directory is not one
    assert protected_reason("..") and protected_reason(str(nest / "home"))
    assert protected_reason(str(nest)) and protected_reason("to-parent")
    assert protected_reason("new-output") is None and protected_reason("mine") is None


def test_replace_only_empty_or_marked_directories(nest):
    cwd = nest / "a" / "b" / "c"
    (cwd / "empty").mkdir()
    assert check_output("empty", force=True, directory=True) is True
    assert check_output("absent", force=False, directory=True) is False
    with pytest.raises(OSError, match="already exists"):
        check_output("empty", force=False, directory=True)
    with pytest.raises(OSError, match="is not"):  # no marker, or another command's
        check_output("mine", force=True, directory=True, owned=owned_by("export"))
    write_mark(cwd / "mine", "gallery")
    with pytest.raises(OSError, match="is not"):
        check_output("mine", force=True, directory=True, owned=owned_by("export"))
    assert check_output("mine", force=True, directory=True, owned=owned_by("gallery"))
    (cwd / "afile").write_text("x")
    with pytest.raises(OSError, match="not a directory"):
        check_output("afile", force=True, directory=True)
    with pytest.raises(OSError, match="is a directory"):
        check_output("mine", force=True, directory=False)
    # A marker that is a link, or whose details differ, is no marker.
    (cwd / "linked").mkdir()
    os.symlink(cwd / "mine" / MARK, cwd / "linked" / MARK)
    assert not has_mark(cwd / "linked", "gallery")
    write_mark(cwd / "mine", "export", format="iiif")
    assert has_mark(cwd / "mine", "export", format="iiif")
    assert not has_mark(cwd / "mine", "export", format="dzi")


def test_replace_dir_swaps_a_marked_directory(tmp_path):
    old, new = tmp_path / "out", tmp_path / "new"
    for d, text in ((old, "old"), (new, "new")):
        d.mkdir()
        (d / "f.txt").write_text(text)
        write_mark(d, "export")
    replace_dir(new, old, owned=owned_by("export"))
    assert (old / "f.txt").read_text() == "new" and not new.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    # A directory that lost its mark while the new one was written is not replaced.
    (tmp_path / "next").mkdir()
    (old / MARK).unlink()
    with pytest.raises(OSError, match="changed while"):
        replace_dir(tmp_path / "next", old, owned=owned_by("export"))
    assert (old / "f.txt").read_text() == "new"


def test_images_read_back_equal_what_was_written(tmp_path, rng):
    rgb = rng.integers(0, 256, (37, 53, 3), dtype=np.uint8)
    write_image(tmp_path / "a.png", rgb)
    assert np.array_equal(np.asarray(Image.open(tmp_path / "a.png")), rgb)
    write_image(tmp_path / "a.jpg", rgb, quality=95)
    jpg = np.asarray(Image.open(tmp_path / "a.jpg")).astype(int)
    assert jpg.shape == rgb.shape and np.abs(jpg - rgb).mean() < 20
    write_image(tmp_path / "a.tif", rgb)
    assert np.array_equal(np.asarray(Image.open(tmp_path / "a.tif")), rgb)
    linear = rng.random((9, 11, 3), dtype=np.float32)
    write_image(tmp_path / "a.exr", linear)
    import OpenImageIO as oiio
    assert np.array_equal(oiio.ImageBuf(str(tmp_path / "a.exr")).get_pixels(oiio.FLOAT), linear)
    with pytest.raises(ValueError):
        write_image(tmp_path / "b.png", rgb.astype(np.int64))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr", "a.jpg", "a.png", "a.tif"]


# A child that writes every kind of file past a 20 kB file-size limit: each write must fail
# with one OSError naming the file (EFBIG: SIGXFSZ ignored), and nothing may be left.
_FSIZE_CHILD = textwrap.dedent("""
    import resource, sys, numpy as np
    from gigascroll import outputs
    outputs.ignore_sigxfsz()
    resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))
    d = sys.argv[1]
    noise = np.random.default_rng(0).integers(0, 256, (200, 200, 3), dtype=np.uint8)
    jobs = [(ext, noise) for ext in ("png", "jpg", "tif")]
    jobs.append(("exr", noise.astype(np.float32)))
    for ext, img in jobs:
        try:
            outputs.write_image(f"{d}/c.{ext}", img)
            print(ext, "written")
        except OSError as e:
            print(ext, "OSError", str(e).splitlines()[0])
    try:
        outputs.write_bytes(f"{d}/raw.bin", bytes(100000))
    except OSError as e:
        print("raw", "OSError", e.errno == 27, str(e))
""")


def _check_full(out: str, d: Path) -> None:
    lines = out.strip().splitlines()
    assert len(lines) == 5, out
    assert all(" OSError " in ln and ln.count("cannot write") == 1 for ln in lines), out
    assert list(d.iterdir()) == [], list(d.iterdir())


def test_file_size_limit_fails_cleanly(tmp_path):
    r = subprocess.run([sys.executable, "-c", _FSIZE_CHILD, str(tmp_path)], capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    _check_full(r.stdout, tmp_path)
    assert "raw OSError True" in r.stdout


@pytest.fixture
def tiny_disk(tmp_path):
    """A 1 MiB tmpfs (skipped where mounting is not permitted)."""
    d = tmp_path / "disk"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()[:100]}")
    try:
        yield d
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


def test_full_disk_fails_cleanly(tiny_disk):
    (tiny_disk / "filler").write_bytes(bytes(1024 * 1024 - 16 * 1024))
    before = {p.name for p in tiny_disk.iterdir()}
    noise = np.random.default_rng(1).integers(0, 256, (300, 300, 3), dtype=np.uint8)
    for ext in ("png", "jpg", "tif"):
        with pytest.raises(OSError, match=f"cannot write .*c.{ext}"):
            write_image(tiny_disk / f"c.{ext}", noise)
    with pytest.raises(OSError) as e:
        write_bytes(tiny_disk / "raw.bin", bytes(100000))
    assert e.value.errno == errno.ENOSPC
    assert {p.name for p in tiny_disk.iterdir()} == before


def test_sigterm_runs_the_cleanup_once(tmp_path):
    child = textwrap.dedent("""
        import os, shutil, signal, sys, time
        from pathlib import Path
        from gigascroll.outputs import Interrupted, signals_interrupt, temp_dir
        out = Path(sys.argv[1])
        tmp = temp_dir(out)
        with signals_interrupt():
            try:
                print("started", flush=True)
                time.sleep(60)
            except Interrupted as e:
                os.kill(os.getpid(), signal.SIGTERM)  # a second signal during cleanup: ignored
                time.sleep(0.2)
                shutil.rmtree(tmp)
                print("cleaned", e.signum, flush=True)
    """)
    p = subprocess.Popen([sys.executable, "-c", child, str(tmp_path / "o")],
                         stdout=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "started"
        assert [x.name for x in tmp_path.iterdir()] == [f"o.tmp-{p.pid}"]
        p.send_signal(signal.SIGTERM)
        out, _ = p.communicate(timeout=60)
    finally:
        p.kill()
    assert out.strip() == f"cleaned {int(signal.SIGTERM)}" and p.returncode == 0
    assert list(tmp_path.iterdir()) == []


def test_temporary_names_never_reuse_an_existing_one(tmp_path):
    taken = tmp_path / f"o.tmp-{os.getpid()}"
    taken.mkdir()
    (taken / "user.txt").write_text("keep")
    made = outputs.temp_dir(tmp_path / "o")
    assert made != taken and made.is_dir() and (taken / "user.txt").read_text() == "keep"


def test_next_run_removes_only_provable_leftovers_of_dead_runs(tmp_path):
    """A run killed outright (SIGKILL) leaves its marked temporary; the next run removes it,
    and nothing that merely has such a name, nor a live process' temporary."""
    from gigascroll.outputs import remove_stale_temps, temp_dir
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = tmp_path / "x"
    stale = tmp_path / f"x.tmp-{dead.pid}"
    stale_old = tmp_path / f"x.tmp-{dead.pid}-old"
    for d in (stale, stale_old):
        d.mkdir()
        write_mark(d, "export", format="iiif")
        (d / "info.json").write_text("{}")
    unmarked = tmp_path / f"x.tmp-{dead.pid}-1"  # a user's directory with such a name
    unmarked.mkdir()
    (unmarked / "keep.txt").write_text("keep")
    other_kind = tmp_path / f"x.tmp-{dead.pid}-2"  # another export format's
    other_kind.mkdir()
    write_mark(other_kind, "export", format="dzi")
    live = tmp_path / f"x.tmp-{os.getppid()}"  # a live process (our parent)
    live.mkdir()
    write_mark(live, "export", format="iiif")
    mine = temp_dir(out, command="export", format="iiif")
    assert has_mark(mine, "export", format="iiif")
    removed = remove_stale_temps(out, "export", format="iiif")
    assert sorted(removed) == sorted([stale, stale_old])
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted([unmarked.name, other_kind.name, live.name, mine.name])
    assert (unmarked / "keep.txt").read_text() == "keep"


ROOM_PAST_LIMIT = textwrap.dedent("""
    import resource, sys
    from gigascroll import outputs
    from gigascroll.gallery import builtin_room
    from gigascroll.room.files import save_room
    from gigascroll.room.sizes import PaintingSize
    outputs.ignore_sigxfsz()
    spec = builtin_room("scroll", [PaintingSize("p", 6000, 400)])
    resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))  # every format is larger
    for ext in ("glb", "gltf", "obj", "ply"):
        try:
            save_room(spec, f"{sys.argv[1]}/room.{ext}")
            print(ext, "written")
        except OSError as e:
            print(ext, "OSError", e.errno == 27)
""")


def test_a_room_file_past_the_size_limit_leaves_nothing(tmp_path):
    """save_room writes through outputs: past RLIMIT_FSIZE each format is an OSError (EFBIG)
    and no file or temporary is left (it once left ROOM.part)."""
    r = subprocess.run([sys.executable, "-c", ROOM_PAST_LIMIT, str(tmp_path)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["glb", "OSError", "True", "gltf", "OSError", "True",
                                "obj", "OSError", "True", "ply", "OSError", "True"]
    assert sorted(p.name for p in tmp_path.iterdir()) == []

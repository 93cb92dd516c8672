"""Fuzz: the commands' outputs (issue 43's families 1 and 2, and its one-line errors of
commands). Each case runs a command as a user would, in a forked child (fuzz_support), and is
judged by the file tree itself:

- data loss: `export --force`, `pack --force`, `gallery --out` and a sharded `pack` aimed at
  `.`, `..`, `/`, the home directory, an ancestor of the working directory, a directory
  without the command's marker, or a link to one of them: exit 2 with one line, every file
  still there byte for byte;
- full disk: every writer past RLIMIT_FSIZE (and on a full 1 MiB tmpfs where one can be
  mounted): exit 2 with one line, nothing written and no temporary left; SIGTERM during
  `gallery` and `export`: no temporary left;
- misused options: --screenshot patterns, a path's frame rate the video cannot take,
  --quit-after NaN, radii a float32 cannot hold, Mitsuba slots out of range, a walk whose
  frame source was built from another pack, and tqdm's warning under 1 Mpixel."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gigascroll import build_pack
from gigascroll.outputs import MARK


def tree(root: Path) -> dict:
    """Every file and link under root (links not followed) with its bytes."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in filenames + [d for d in dirnames if os.path.islink(os.path.join(dirpath, d))]:
            p = Path(dirpath) / name
            out[str(p.relative_to(root))] = os.readlink(p) if p.is_symlink() else p.read_bytes()
    return out


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A small image, its pack (two paintings) and a second, different pack."""
    d = tmp_path_factory.mktemp("outputs-inputs")
    rng = np.random.default_rng(7)
    img = rng.integers(0, 256, (40, 60, 3), dtype=np.uint8)
    from PIL import Image
    Image.fromarray(img).save(d / "a.png")
    build_pack([img, img[:, ::-1].copy()], d / "p.pack", tile_size=16, border=2,
               names=["one", "two"])
    build_pack([rng.integers(0, 256, (30, 50, 3), dtype=np.uint8)] * 2, d / "q.pack",
               tile_size=16, border=2, names=["one", "two"])
    return {"image": str(d / "a.png"), "pack": str(d / "p.pack"), "other": str(d / "q.pack")}


def _nest(root: Path) -> Path:
    """A working directory three levels down with user files at every level, a home beside
    it and links to the places that must never be replaced; returns the working directory."""
    home, cwd = root / "home", root / "a" / "b" / "c"
    for d in (home, cwd / "mine", cwd / "mine_files"):  # mine_files: a Deep Zoom's name
        d.mkdir(parents=True)
    for d in (root, root / "a", root / "a" / "b", cwd, home, cwd / "mine", cwd / "mine_files"):
        (d / "precious.txt").write_text(f"user data in {d.name}")
    (cwd / "mine" / "manifest.json").write_text('{"format": "not a pack"}')
    for name, target in (("to-parent", ".."), ("to-home", str(home)), ("to-mine", "mine"),
                         ("to-cwd", "."), ("to-mine_files", "mine_files")):
        os.symlink(target, cwd / name)
    return cwd


PLACES = [".", "..", "../..", "/", "HOME", "mine", "to-parent", "to-home", "to-mine",
          "to-cwd", "../c", "mine/.."]
WRITERS = {
    "export iiif": lambda i, o: ["export", i["pack"], "-o", o, "--format", "iiif", "--force"],
    "export dzi": lambda i, o: ["export", i["pack"], "-o", o, "--format", "dzi", "--force"],
    "export tiff": lambda i, o: ["export", i["pack"], "-o", o, "--format", "tiff", "--force"],
    "pack": lambda i, o: ["pack", i["image"], "-o", o, "--force"],
    "pack sharded": lambda i, o: ["pack", i["image"], "-o", o, "--force", "--workers", "1",
                                  "--resume"],
    "gallery": lambda i, o: ["gallery", i["pack"], "--out", o, "--eye", "16x16",
                             "--photons", "64", "--seconds", "0.02", "--no-video",
                             "--no-oracle"],
}


def _run_with_home(worker, argv, cwd: Path, home: Path | None, prelude: str = ""):
    code = textwrap.dedent(f"""
        import os, sys
        if {str(home) if home else None!r}:
            os.environ["HOME"] = {str(home)!r}
        {prelude}
        from gigascroll import cli
        raise SystemExit(cli.main({argv!r}))
    """)
    return worker.run({"kind": "python", "code": code, "cwd": str(cwd)}, timeout=120)


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_refused_places_keep_every_file(fork_worker, inputs, tmp_path, writer):
    cwd = _nest(tmp_path)
    before = tree(tmp_path)
    for place in PLACES:
        count_case("outputs: refused places")
        target = str(tmp_path / "home") if place == "HOME" else place
        o = _run_with_home(fork_worker, WRITERS[writer](inputs, target), cwd, tmp_path / "home")
        assert cli_message_ok(o) is None and o.code == 2, (writer, place, o.describe())
        assert "refusing" in o.stderr or "not a tile pack" in o.stderr, (writer, place, o.stderr)
        assert tree(tmp_path) == before, (writer, place)


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_replacing_its_own_output_works(fork_worker, inputs, tmp_path, writer):
    """The control of the refusals: the same command replaces what it made itself."""
    cwd = _nest(tmp_path)
    argv = WRITERS[writer](inputs, "out")
    first = WRITERS["pack"](inputs, "out") if writer == "pack sharded" else argv  # one Dask run
    for attempt, args in enumerate((first, argv)):
        o = _run_with_home(fork_worker, args, cwd, tmp_path / "home")
        assert o.code == 0, (writer, attempt, o.describe())
    left = sorted(p.name for p in cwd.iterdir() if p.name.startswith(("out", ".out")))
    assert left == (["out.dzi", "out_files"] if writer == "export dzi" else ["out"]), left


def test_sharded_build_keeps_unrelated_shard_directories(fork_worker, inputs, tmp_path):
    cwd = _nest(tmp_path)
    shards = cwd / "z.pack.shards"
    shards.mkdir()
    (shards / "tiles-00000.bin").write_bytes(b"someone else's")
    (shards / "shard-00000.json").write_text("{}")
    # A shard directory of another output, renamed: its mark names that output, not this one.
    other = cwd / "y.pack.shards"
    other.mkdir()
    (other / MARK).write_text(json.dumps({"made_by": "gigascroll", "command": "pack-shards",
                                          "output": str(cwd / "y.pack")}))
    (other / "tiles-00000.bin").write_bytes(b"y's")
    before = tree(tmp_path)
    for extra in ([], ["--resume"], ["--force"], ["--resume", "--force"]):
        for out in ("z.pack", "y2.pack"):
            if out == "y2.pack":
                os.rename(other, cwd / "y2.pack.shards")
            count_case("outputs: shard directories")
            o = _run_with_home(fork_worker, ["pack", inputs["image"], "-o", out, "--workers", "1",
                                             *extra], cwd, tmp_path / "home")
            if out == "y2.pack":
                os.rename(cwd / "y2.pack.shards", other)
            assert cli_message_ok(o) is None and o.code == 2, o.describe()
            assert "shard directory" in o.stderr
            assert tree(tmp_path) == before
    assert not (cwd / "z.pack").exists()


# ----------------------------------------------------------------------------- full disk

FULL = {
    "render png": ["render", "cornell", "-o", "{d}/c.png", "--width", "200", "--height", "200",
                   "--photons", "500", "--spp", "1"],
    "render jpg": ["render", "cornell", "-o", "{d}/c.jpg", "--width", "400", "--height", "400",
                   "--photons", "500", "--spp", "1"],
    "render exr": ["render", "cornell", "-o", "{d}/c.exr", "--width", "200", "--height", "200",
                   "--photons", "500", "--spp", "1"],
    "render tif": ["render", "cornell", "-o", "{d}/c.tif", "--width", "200", "--height", "200",
                   "--photons", "500", "--spp", "1"],
    "synth": ["synth", "--width", "600", "--height", "300", "-o", "{d}/s.tif"],
    "pack": ["pack", "{image}", "-o", "{d}/p.pack", "--tile-size", "16", "--border", "2"],
    "export iiif": ["export", "{big}", "-o", "{d}/x", "--format", "iiif"],
    "export dzi": ["export", "{big}", "-o", "{d}/x", "--format", "dzi"],
    "export tiff": ["export", "{big}", "-o", "{d}/x.tif", "--format", "tiff"],
    "gallery": ["gallery", "{pack}", "--out", "{d}/g", "--eye", "32x32", "--photons", "64",
                "--seconds", "0.05", "--no-oracle"],
}


@pytest.fixture(scope="module")
def big_inputs(inputs, tmp_path_factory):
    """A pack whose exports are well above the file-size limit of the cases (noise)."""
    d = tmp_path_factory.mktemp("outputs-big")
    img = np.random.default_rng(3).integers(0, 256, (200, 300, 3), dtype=np.uint8)
    build_pack(img, d / "big.pack", tile_size=128, border=4)
    return dict(inputs, big=str(d / "big.pack"))


def _full_case(worker, argv, d: Path, cwd: Path, limit: int | None):
    prelude = ""
    if limit is not None:
        prelude = (f"import resource; resource.setrlimit(resource.RLIMIT_FSIZE, "
                   f"({limit}, {limit}))")
    return _run_with_home(worker, argv, cwd, None, prelude)


def _expect_nothing_written(o, d: Path, before: set, what: str) -> None:
    assert cli_message_ok(o) is None and o.code == 2, (what, o.describe())
    assert "cannot write" in o.stderr or "write failed" in o.stderr, (what, o.stderr)
    assert {p.name for p in d.iterdir()} == before, (what, sorted(p.name for p in d.iterdir()))


@pytest.mark.parametrize("what", sorted(FULL))
def test_file_size_limit_leaves_nothing(fork_worker, big_inputs, tmp_path, what):
    count_case("outputs: file-size limit")
    argv = [a.format(d=tmp_path, **big_inputs) for a in FULL[what]]
    # The limit stays above the case's stdout/stderr files (a few hundred bytes).
    o = _full_case(fork_worker, argv, tmp_path, tmp_path, 6000)
    _expect_nothing_written(o, tmp_path, set(), what)
    # The control: without the limit the same command writes its output.
    o = _full_case(fork_worker, argv, tmp_path, tmp_path, None)
    assert o.code == 0, (what, o.describe())
    assert any(tmp_path.iterdir())


@pytest.fixture(scope="module")
def tiny_disk(tmp_path_factory):
    """A 1 MiB tmpfs, nearly full (skipped where mounting is not permitted)."""
    d = tmp_path_factory.mktemp("outputs-disk")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()[:100]}")
    (d / "filler").write_bytes(bytes(1024 * 1024 - 4096))  # one page left
    try:
        yield d
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


@pytest.mark.parametrize("what", sorted(FULL))
def test_full_disk_leaves_nothing(fork_worker, big_inputs, tiny_disk, tmp_path, what):
    count_case("outputs: full disk")
    before = {p.name for p in tiny_disk.iterdir()}
    argv = [a.format(d=tiny_disk, **big_inputs) for a in FULL[what]]
    o = _full_case(fork_worker, argv, tiny_disk, tmp_path, None)
    _expect_nothing_written(o, tiny_disk, before, what)


# ----------------------------------------------------------------------------- SIGTERM

def _sigterm_when(argv: list[str], cwd: Path, started) -> subprocess.CompletedProcess:
    """Runs `gigascroll ARGV`, sends SIGTERM once started(cwd) holds, returns the outcome."""
    env = dict(os.environ, TQDM_DISABLE="1")
    p = subprocess.Popen([sys.executable, "-m", "gigascroll", *argv], cwd=cwd, env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not started(cwd) and p.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert p.poll() is None, "the command ended before it could be stopped"
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=120)
    finally:
        p.kill()
    return subprocess.CompletedProcess(argv, p.returncode, out, err)


@pytest.fixture(scope="module")
def many_tiles(tmp_path_factory):
    """A pack of some 20 000 small tiles: an export of it runs for seconds."""
    d = tmp_path_factory.mktemp("outputs-many")
    img = np.random.default_rng(5).integers(0, 256, (1200, 1500, 3), dtype=np.uint8)
    build_pack(img, d / "many.pack", tile_size=16, border=2)
    return str(d / "many.pack")


@pytest.mark.parametrize("fmt", ["iiif", "dzi", "tiff"])
def test_sigterm_during_export_leaves_no_temporary(many_tiles, tmp_path, fmt):
    def started(cwd):  # some tiles are written
        tmp = list(cwd.glob("x*.tmp-*"))
        return bool(tmp) and (fmt == "tiff" or sum(1 for _ in tmp[0].rglob("*.jpg")) > 20)
    out = "x.tif" if fmt == "tiff" else "x"
    r = _sigterm_when(["export", many_tiles, "-o", out, "--format", fmt, "--threads", "1"],
                      tmp_path, lambda cwd: started(cwd) or bool(list(cwd.glob(".x.tmp-*"))))
    assert r.returncode == 128 + signal.SIGTERM, r.stderr
    assert r.stderr.strip().splitlines()[-1].endswith("interrupted (stopped by SIGTERM)")
    assert "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_sigterm_during_gallery_leaves_no_temporary(inputs, tmp_path):
    def started(cwd):  # frames are being written
        return any(cwd.glob(".g.tmp-*/frames/*.png"))
    r = _sigterm_when(["gallery", inputs["pack"], "--out", "g", "--eye", "64x64", "--photons",
                       "500", "--seconds", "20", "--png-every", "1", "--no-oracle"], tmp_path,
                      started)
    assert r.returncode == 128 + signal.SIGTERM, r.stderr
    assert "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- one line

@given(pattern=st.one_of(
    st.text(alphabet="{}n0x:!r.s/pngjgif-%", max_size=16),
    st.sampled_from(["{x}.png", "{0}.png", "{}.png", "{n.real}.png", "{n[0]}.png", "{n:s}.png",
                     "{n}.gif", "{n}", "shot", "{n:>999999999}.png", "{{n}}.png", "nodir/{n}.png",
                     "{n!z}.png", "{n}.PNG", "{n:05d}.jpg"])))
@fuzz_settings(25)
def test_screenshot_patterns(fork_worker, tmp_path_factory, pattern):
    """No display: a bad pattern is one line naming --screenshot, a good one reaches the
    display check (one line too); nothing is written either way."""
    count_case("outputs: screenshot patterns")
    d = tmp_path_factory.mktemp("shots")
    code = textwrap.dedent(f"""
        import os
        os.environ.pop("DISPLAY", None); os.environ.pop("WAYLAND_DISPLAY", None)
        from gigascroll import cli
        raise SystemExit(cli.main(["view", "nopack", "--screenshot", {pattern!r}]))
    """)
    o = fork_worker.run({"kind": "python", "code": code, "cwd": str(d)})
    assert cli_message_ok(o) is None and o.code == 2, (pattern, o.describe())
    assert "--screenshot" in o.stderr or "display" in o.stderr, o.stderr
    if "display" in o.stderr:  # accepted: a pattern of .png/.jpg names, only {n}, distinct
        names = {pattern.format(n=k) for k in (0, 1, 2)}
        assert len(names) == 3 or "{" not in pattern.replace("{{", "")
        assert all(Path(n).suffix.lower() in (".png", ".jpg", ".jpeg") for n in names)
    assert list(d.iterdir()) == []


@pytest.mark.parametrize("argv, needle", [
    (["view", "x", "--quit-after", "nan"], "--quit-after"),
    (["view", "x", "--quit-after", "-1"], "--quit-after"),
    (["view", "x", "--quit-after", "inf"], "--quit-after"),
    (["render", "cornell", "-o", "c.png", "--radius", "1e-46"], "radius"),
    (["render", "cornell", "-o", "c.png", "--radius", "1e-40"], "radius"),
    (["render", "cornell", "-o", "c.png", "--radius", "1e39"], "radius"),
    (["render", "--room", "scroll", "--pack", "{pack}", "-o", "c.png", "--radius", "1e-46",
      "--width", "16", "--height", "16", "--photons", "64"], "radius"),
    (["gallery", "{pack}", "--path", "{slow}", "--out", "g", "--eye", "16x16"], "frame rate"),
    (["gallery", "{pack}", "--path", "{fast}", "--out", "g", "--eye", "16x16"], "fps"),
])
def test_misused_options_are_one_line(fork_worker, inputs, tmp_path, argv, needle):
    count_case("outputs: misused options")
    from gigascroll.views import CameraPath
    for name, fps in (("slow", 1e-9), ("fast", 1e5)):
        d = {"name": "p", "fps": fps, "position": [[0, 1.6, 2.0]], "forward": [[0, 0, -1.0]],
             "up": [[0, 1.0, 0]], "magnifier_target": None, "magnifier_normal": None}
        (tmp_path / f"{name}.json").write_text(json.dumps(d))
    assert CameraPath.load(tmp_path / "slow.json").fps == 1e-9  # a valid path, not a video's
    args = [a.format(pack=inputs["pack"], slow=tmp_path / "slow.json",
                     fast=tmp_path / "fast.json") for a in argv]
    o = fork_worker.run({"kind": "cli", "argv": args, "cwd": str(tmp_path)})
    assert cli_message_ok(o) is None and o.code == 2, o.describe()
    assert needle in o.stderr, o.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fast.json", "slow.json"]


def test_mitsuba_level_names_its_range(inputs):
    from gigascroll import TilePack
    from gigascroll.gallery import Gallery, builtin_room
    pack = TilePack(inputs["pack"])
    g = Gallery.from_room(builtin_room("hall", pack), pack)
    n = len(g.slot_paintings)
    assert n >= 2
    for slot in (n, 99, -1, -n, 1.0, True, "0", None):
        with pytest.raises(ValueError, match=rf"\[0, {n - 1}\]"):
            g.mitsuba_level(slot)
    for slot in range(n):  # the control: each slot's level is the finest at most max_width
        p = pack.paintings[g.slot_paintings[slot]]
        want = next((lv for lv, (w, _) in enumerate(p.level_sizes) if w <= 20), p.levels - 1)
        assert g.mitsuba_level(slot, max_width=20) == want
    with pytest.raises(ValueError, match="max_width"):
        g.mitsuba_level(0, max_width=0)


def test_walk_refuses_a_source_of_another_pack(inputs):
    from gigascroll import TilePack
    from gigascroll.gallery import builtin_room
    from gigascroll.walk.gallery_walk import ExhibitionSource, GalleryWalk, walk_path
    pack, other = TilePack(inputs["pack"]), TilePack(inputs["other"])
    room = builtin_room("scroll", pack)
    source = ExhibitionSource(room, pack)
    path = walk_path(room, 0.02)
    with pytest.raises(ValueError, match="another pack"):
        GalleryWalk(source, other, path, eye=(16, 16), oracle=False)
    # The control: the same pack opened again is the same pack.
    GalleryWalk(source, TilePack(inputs["pack"]), path, eye=(16, 16), oracle=False)


def test_pack_progress_under_one_megapixel_does_not_warn():
    """The pack's Mpixel bar takes band shares whose float sum passes a small total; tqdm
    warns for that (the control below shows it does), the pack's bar stops at its total."""
    import io

    from tqdm import TqdmWarning, tqdm

    from gigascroll.pack.build import _mpx_bar
    shares = [0.1] * 3  # 0.3 Mpixel in three bands; their float sum passes 0.3 by 4e-17
    assert sum(shares) > 0.3
    for cls, warns in ((tqdm, True), (_mpx_bar(), False)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            bar = cls(total=0.3, file=io.StringIO(), ncols=80, mininterval=0)
            for s in shares:
                bar.update(s)
            bar.refresh()
            bar.close()
        assert any(issubclass(w.category, TqdmWarning) for w in caught) == warns
        if not warns:
            assert bar.n == pytest.approx(0.3, abs=1e-12) and bar.n <= 0.3


@given(value=st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                       st.sampled_from([1e-46, 1e-39, 2.0 ** -126, 2.0 ** -127, 3.4028234663852886e38,
                                        3.5e38, 0.0, -0.0, 5e-324])))
@fuzz_settings(60)
def test_float32_values_are_checked_against_numpy(value):
    """positive_float32 takes exactly the positive normal float32 range (numpy's finfo)."""
    from gigascroll.errors import positive_float32
    f32 = np.finfo(np.float32)
    ok = bool(float(f32.tiny) <= value <= float(f32.max))
    if ok:
        assert positive_float32(value, "x") == value
        assert np.float32(value) > 0 and np.isfinite(np.float32(value))
    else:
        with pytest.raises(ValueError, match="float32"):
            positive_float32(value, "x")


@pytest.mark.parametrize("value", [1e-46, 1e-39, 1e39, float("nan"), 0.0, -1.0])
def test_float32_options_of_the_api(inputs, value):
    from gigascroll import TilePack, builtin_scene, render
    from gigascroll.gallery import Gallery, builtin_room
    from gigascroll.runtime import VirtualTexture
    scene, cam = builtin_scene("cornell", resolution=(8, 8))
    with pytest.raises(ValueError, match="radius"):
        render(scene, cam, photons=64, radius=value)
    with pytest.raises(ValueError, match="alpha"):
        render(scene, cam, photons=64, progressive=True, passes=1, alpha=value)
    pack = TilePack(inputs["pack"])
    g = Gallery.from_room(builtin_room("scroll", pack), pack)
    with pytest.raises(ValueError, match="radius"):
        g.light(VirtualTexture(pack, slots=(8, 8)), photons=64, radius=value)


_VIDEO_CHILD = textwrap.dedent("""
    import resource, sys, numpy as np
    from gigascroll.outputs import ignore_sigxfsz
    from gigascroll.walk.video import VideoWriter
    ignore_sigxfsz()
    if sys.argv[2] != "none":
        resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[2]), int(sys.argv[2])))
    w = VideoWriter(sys.argv[1], (64, 48), 30, ["-crf", "20", "-preset", "veryfast"])
    rng = np.random.default_rng(0)
    try:
        for i in range(40):
            w.send(rng.integers(0, 256, (48, 64, 3), dtype=np.uint8))
        w.close()
        print("closed")
    except OSError as e:
        w.abort()
        print("OSError", e)
""")


def test_video_past_the_size_limit_is_an_error(tmp_path):
    """The walk's video: ffmpeg's exit status is checked (imageio-ffmpeg's writer did not),
    so a video cut short is one OSError; the control is read back frame by frame."""
    out = tmp_path / "w.mp4"
    r = subprocess.run([sys.executable, "-c", _VIDEO_CHILD, str(out), "20000"],
                       capture_output=True, text=True, timeout=120)
    assert r.stdout.strip() == f"OSError cannot write {out}: File too large (the file-size limit)", r
    out.unlink()
    r = subprocess.run([sys.executable, "-c", _VIDEO_CHILD, str(out), "none"],
                       capture_output=True, text=True, timeout=120)
    assert r.stdout.strip() == "closed", r
    import imageio_ffmpeg
    frames = imageio_ffmpeg.read_frames(str(out))
    assert next(frames)["size"] == (64, 48) and sum(1 for _ in frames) == 40

"""The gallery walk (gigascroll.walk.gallery_walk, gigascroll gallery): streamed frames converge
to their all-resident oracle, stops sharpen within the seed's latency, the outputs are whole
(PNG, MP4 decoded back by ffmpeg, report, JSON), and bad input fails in one line."""

import dataclasses
import json

import numpy as np
import pytest

from gigascroll import views as v
from gigascroll.gallery import builtin_room
from gigascroll.walk.gallery_walk import (ExhibitionSource, GallerySource, GalleryWalk, compose_frame,
                                     lens_in_view, parent_keys, stops_of, tone_map, walk_path)


@pytest.fixture(scope="module")
def room(small_scroll_pack):
    return builtin_room("scroll", small_scroll_pack)


def test_streamed_frames_converge_to_the_oracle(room, small_scroll_pack):
    """Few slots and few loads a frame: frames are wrong while the tiles stream in, and once
    the camera stands still every frame equals its oracle (error exactly 0)."""
    path = walk_path(room, seconds=0.6)
    src = ExhibitionSource(room, small_scroll_pack)
    walk = GalleryWalk(src, small_scroll_pack, path, eye=(64, 68), per_frame=2,
                       wait_loads=True, slots=(20, 20))
    s = walk.run()
    r = walk.records
    assert s["frames"] == len(path)
    errors = np.array([x["error"] for x in r])
    assert errors.max() > 0            # streaming shows up in accuracy
    assert r[-1]["error"] == 0.0 and r[-1]["hit_rate"] == 1.0
    stops = s["stops"]
    assert len(stops) >= 2
    for st in stops:
        # Each stop ends sharp and equal to its oracle.
        assert st["display_latency_frames"] is not None
        assert st["exact_after_frames"] is not None
        assert st["exact_after_frames"] <= st["frames"]
    assert all(x["issued"] <= 2 for x in r)


def test_a_stop_sharpens_within_two_frames_at_the_seed_threshold(room, small_scroll_pack):
    path = walk_path(room, seconds=0.6)
    walk = GalleryWalk(ExhibitionSource(room, small_scroll_pack), small_scroll_pack, path,
                       eye=(64, 68), wait_loads=True, oracle=False)
    s = walk.run()
    assert all(st["display_latency_frames"] <= 2 for st in s["stops"])
    assert "error" not in walk.records[0]


def test_lit_walk_reuses_the_left_eye(room, small_scroll_pack):
    src = GallerySource(room, small_scroll_pack, "baked", photons=5000, spacing=0.4,
                        bake_samples=2)
    path = walk_path(room, seconds=0.15)
    walk = GalleryWalk(src, small_scroll_pack, path, eye=(48, 52), wait_loads=True)
    s = walk.run()
    assert 0.5 < s["reused_share"] < 1.0
    assert walk.records[-1]["error"] == 0.0
    for key in ("display_rays_ms", "display_vt_ms", "display_shade_ms", "display_reuse_ms"):
        assert s[key] >= 0


def test_parent_keys_match_the_tile_key_definition():
    keys = np.array([v.pack_request(0, 0, 5, 3), v.pack_request(1, 2, 1, 0),
                     v.pack_request(0, 3, 0, 0), v.NO_REQUEST], np.uint64)
    got = parent_keys(keys, np.array([4, 4]))
    want = sorted([v.pack_request(0, 1, 2, 1), v.pack_request(1, 3, 0, 0)])
    assert got.tolist() == want   # level 3 of painting 0 is its coarsest: no parent


def test_stops_and_frame_composition():
    rec = [{"frame": i, "moving": m, "hit_rate": h, "error": e} for i, (m, h, e) in enumerate(
        [(True, 1, 0), (False, 0.5, 1), (False, 1, 0.1), (False, 1, 0), (True, 1, 0), (False, 1, 0)])]
    # frames 1..4 show one pose (frame 4 moves on afterwards); frame 5 is alone.
    assert stops_of(rec) == [{"first_frame": 1, "frames": 4, "display_latency_frames": 2,
                              "exact_after_frames": 3}]
    left = np.zeros((40, 30, 3), np.float32)
    right = np.ones((40, 30, 3), np.float32)
    mag = np.full((16, 16, 3), 0.5, np.float32)
    frame = compose_frame(left, right, mag, ((np.array([15.0, 20.0]), 6.0), None))
    assert frame.shape == (40, 60, 3)
    assert np.allclose(frame[20, 15], 0.5)          # the lens in the left eye
    assert np.allclose(frame[2, 32], 1.0)           # the right eye untouched away from the inset
    assert np.allclose(frame[39, 59], 0.5)          # the inset, lower right
    assert tone_map(np.array([[[0.0, 1.0, 0.5]]]), tone="clip")[0, 0].tolist() == [0, 255, 188]
    cam = v.Camera((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), 1.0, 1.0, 100, 100)
    c, r = lens_in_view(cam, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), 0.5)
    assert np.allclose(c, [50, 50]) and r == pytest.approx(25)
    assert lens_in_view(cam, np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0]), 0.5) is None


def test_walk_bad_input(room, small_scroll_pack):
    path = walk_path(room, seconds=0.1)
    src = ExhibitionSource(room, small_scroll_pack)
    with pytest.raises(ValueError, match="eye resolution"):
        GalleryWalk(src, small_scroll_pack, path, eye=(0, 0))
    with pytest.raises(ValueError, match="threshold"):
        GalleryWalk(src, small_scroll_pack, path, eye=(32, 32), per_frame=0)
    with pytest.raises(ValueError, match="seconds"):
        walk_path(room, seconds=float("nan"))
    missing = dataclasses.replace(room, paintings=[dataclasses.replace(room.paintings[0],
                                                                       painting="nowhere")])
    with pytest.raises(ValueError, match="nowhere"):
        ExhibitionSource(missing, small_scroll_pack)


# ------------------------------------------------------------------------------ command line

def test_gallery_command_writes_a_whole_output(gigascroll_cli, tmp_path, small_scroll_pack):
    out = tmp_path / "walk"
    r = gigascroll_cli("gallery", small_scroll_pack.path, "--eye", "32x34", "--seconds", "0.12",
                       "--photons", "3000", "--out", out, "--exr", "--png-every", "5")
    assert r.returncode == 0, r.stderr
    res = json.loads((out / "results.json").read_text())
    n = res["summary"]["frames"]
    assert n == len(res["frames"]) == walk_path(builtin_room("scroll", small_scroll_pack),
                                                 0.12).position.shape[0]
    assert res["frames"][-1]["error"] == 0.0
    for f in ("report.md", "stages.png", "fps.png", "hit_error.png", "latency.png", "walk.mp4"):
        assert (out / f).stat().st_size > 0
    assert "![stage times](stages.png)" in (out / "report.md").read_text()
    pngs = sorted((out / "frames").glob("*.png"))
    assert len(pngs) == len(res["saved_frames"]) and len(list((out / "frames").glob("*.exr"))) == len(pngs)
    import OpenImageIO as oiio
    img = oiio.ImageBuf(str(pngs[-1]))
    assert (img.spec().width, img.spec().height) == (64, 34)
    import imageio_ffmpeg
    reader = imageio_ffmpeg.read_frames(str(out / "walk.mp4"))
    meta = next(reader)
    assert meta["size"] == (64, 34) and meta["fps"] == pytest.approx(90)
    assert sum(1 for _ in reader) == n
    assert not list(tmp_path.glob(".walk.tmp-*"))


@pytest.mark.parametrize("args, message", [
    (["--eye", "0x0"], "--eye"),
    (["--eye", "wide"], "--eye"),
    (["--seconds", "nan"], "--seconds"),
    (["--room", "no-such-room"], "--room"),
])
def test_gallery_command_bad_options(gigascroll_cli, tmp_path, small_scroll_pack, args, message):
    out = tmp_path / "o"
    r = gigascroll_cli("gallery", _pack_path(small_scroll_pack), *args, "--out", out)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (out / "results.json").exists()


def test_gallery_command_bad_files(gigascroll_cli, tmp_path, small_scroll_pack, room):
    # A path with NaN.
    path = walk_path(room, 0.1)
    path.save(tmp_path / "p.json")
    d = json.loads((tmp_path / "p.json").read_text())
    d["position"][3][1] = float("nan")
    (tmp_path / "nan.json").write_text(json.dumps(d))   # writes NaN, as JSON libraries do
    r = gigascroll_cli("gallery", _pack_path(small_scroll_pack), "--path", tmp_path / "nan.json",
                       "--out", tmp_path / "o1", "--photons", "100", "--eye", "16x16")
    assert r.returncode == 2 and "NaN" in r.stderr, r.stderr
    assert not (tmp_path / "o1").exists() and not list(tmp_path.glob(".o1.tmp-*"))
    # A room whose painting the pack lacks.
    from gigascroll.room.files import save_room
    missing = dataclasses.replace(room, paintings=[dataclasses.replace(
        room.paintings[0], painting="absent", name="painting:absent")])
    save_room(missing, tmp_path / "room.glb")
    r = gigascroll_cli("gallery", _pack_path(small_scroll_pack), "--room", tmp_path / "room.glb",
                       "--out", tmp_path / "o2", "--eye", "16x16")
    assert r.returncode == 2 and "absent" in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    # An unwritable --out: a file in the way of its parent.
    (tmp_path / "file").write_text("x")
    r = gigascroll_cli("gallery", _pack_path(small_scroll_pack), "--out", tmp_path / "file" / "o")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    # Not a pack.
    r = gigascroll_cli("gallery", tmp_path, "--out", tmp_path / "o3")
    assert r.returncode == 2 and "not a tile pack" in r.stderr
    # A directory that is not an earlier output is never replaced.
    (tmp_path / "keep").mkdir()
    (tmp_path / "keep" / "mine.txt").write_text("precious")
    r = gigascroll_cli("gallery", _pack_path(small_scroll_pack), "--out", tmp_path / "keep")
    assert r.returncode == 2 and (tmp_path / "keep" / "mine.txt").read_text() == "precious"


def _pack_path(pack):
    return pack.path

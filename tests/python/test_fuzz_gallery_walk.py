"""Fuzz cases for the gallery walk's entry points (hypothesis): the display pass with any
camera, frame composition with any lens, the eye option, the walk's path and tile keys.
Each either works (finite, well-formed output) or raises ValueError / UserError."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings, strategies as st

from gigascroll import _core
from gigascroll import views as v
from gigascroll.commands.gallery import parse_eye
from gigascroll.errors import UserError
from gigascroll.gallery import builtin_room
from gigascroll.walk.gallery_walk import ExhibitionSource, GalleryWalk, compose_frame, parent_keys, walk_path
from gigascroll.runtime import VirtualTexture

FIXTURES = [HealthCheck.function_scoped_fixture]
finite = st.floats(-20, 20, allow_nan=False, allow_infinity=False)
anything = st.floats(allow_nan=True, allow_infinity=True)


@pytest.fixture(scope="module")
def scene(small_scroll_pack):
    room = builtin_room("scroll", small_scroll_pack)
    return (ExhibitionSource(room, small_scroll_pack), VirtualTexture(small_scroll_pack, (30, 30)),
            room)


@settings(max_examples=40, deadline=None, suppress_health_check=FIXTURES)
@given(pos=st.tuples(finite, finite, finite), fwd=st.tuples(finite, finite, finite),
       up=st.tuples(finite, finite, finite), tan=st.floats(0.01, 50), w=st.integers(1, 40),
       h=st.integers(1, 40), reuse=st.booleans(), ratio=st.floats(0, 10),
       tolerance=st.one_of(st.floats(0, 2), anything))
def test_display_pass_any_camera(scene, pos, fwd, up, tan, w, h, reuse, ratio, tolerance):
    src, vt, _ = scene
    try:
        left = v.Camera(pos, fwd, up, tan, tan * h / w, w, h)
        right = v.Camera(tuple(np.add(pos, (0.063, 0, 0))), fwd, up, tan, tan * h / w, w, h)
    except ValueError:
        return  # a degenerate frame (zero or parallel forward and up) is refused by Camera
    d = _core.DisplayPass()
    with np.errstate(over="ignore"):
        as_float32 = float(np.float32(tolerance))  # what the pass receives
    if not (math.isfinite(as_float32) and as_float32 >= 0):
        with pytest.raises(ValueError, match="reuse_lod_tolerance"):
            d.render_stereo(src.scene, src.lighting, vt, left, right, reuse=reuse,
                            edge_depth_ratio=ratio, reuse_lod_tolerance=tolerance)
        return
    a, b = d.render_stereo(src.scene, src.lighting, vt, left, right, reuse=reuse,
                           edge_depth_ratio=ratio, reuse_lod_tolerance=tolerance)
    assert a.shape == b.shape == (h, w, 3)
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and a.min() >= 0 and b.min() >= 0
    st_r = d.right_stats
    assert st_r["traced"] + st_r["reused"] == st_r["pixels"] == w * h


@settings(max_examples=60, deadline=None)
@given(h=st.integers(1, 60), w=st.integers(1, 60), m=st.integers(1, 40),
       lens=st.one_of(st.none(), st.tuples(st.tuples(st.floats(-1e4, 1e4), st.floats(-1e4, 1e4)),
                                            st.floats(0, 1e4))), inset=st.booleans())
def test_compose_frame_any_lens(h, w, m, lens, inset):
    left = np.zeros((h, w, 3), np.float32)
    right = np.ones((h, w, 3), np.float32)
    mag = np.full((m, m, 3), 0.5, np.float32)
    lenses = (None if lens is None else (np.array(lens[0]), lens[1]), None)
    out = compose_frame(left, right, mag, lenses, inset=inset)
    assert out.shape == (h, 2 * w, 3) and np.all(np.isfinite(out))


@settings(max_examples=200, deadline=None)
@given(text=st.one_of(st.text(max_size=20),
                      st.builds(lambda a, b: f"{a}x{b}", st.integers(-5, 40000), st.integers(-5, 40000)),
                      # digit strings past Python's int() limit and zero-padded ones
                      st.builds(lambda a, b: f"{a}x{b}", st.text("0123456789", min_size=1, max_size=6000),
                                st.text("0123456789", min_size=1, max_size=30))),
       option=st.sampled_from(["--eye", "--window"]))
@example(text="0" * 5000 + "64x64", option="--eye").via("Python's int() limit counts zeros")
@example(text="1" * 5000 + "x64", option="--window")
def test_eye_option_any_text(text, option):
    try:
        w, h = parse_eye(text, option)
    except UserError as e:
        assert str(e).startswith(option) and len(str(e)) < 200
        return
    a, b = (int(x.strip().lstrip("0") or "0") for x in text.lower().split("x"))  # what it says
    assert (w, h) == (a, b) and 16 <= w <= 16384 and 16 <= h <= 16384


@settings(max_examples=40, deadline=None, suppress_health_check=FIXTURES)
@given(seconds=anything, distance=st.floats(0.05, 3), close=st.floats(0.05, 3),
       fps=st.floats(1, 240))
def test_walk_path_any_parameters(scene, seconds, distance, close, fps):
    _, _, room = scene
    try:
        path = walk_path(room, seconds, fps=fps, distance=distance, close=close)
    except ValueError:
        assert not (math.isfinite(seconds) and 0 < seconds <= 3600)
        return
    assert len(path) >= 14 and np.all(np.isfinite(path.position))
    assert path.fps == fps


@settings(max_examples=100, deadline=None)
@given(keys=st.lists(st.tuples(st.integers(0, 3), st.integers(0, 9), st.integers(0, 400),
                               st.integers(0, 400)), max_size=30))
def test_parent_keys_any_requests(keys):
    levels = np.array([10, 4, 7, 1])
    arr = np.array([v.pack_request(*k) for k in keys] + [v.NO_REQUEST], np.uint64)
    got = parent_keys(arr, levels)
    p, l, x, y = (a.astype(int) for a in v.unpack_requests(got)) if got.size else ([],) * 4
    want = {(pp, ll + 1, xx >> 1, yy >> 1) for pp, ll, xx, yy in keys if ll + 1 < levels[pp]}
    assert set(zip(map(int, p), map(int, l), map(int, x), map(int, y))) == want


@settings(max_examples=20, deadline=None, suppress_health_check=FIXTURES)
@given(w=st.integers(-3, 70), h=st.integers(-3, 70), per_frame=st.integers(-2, 40),
       magnifier=st.booleans())
def test_walk_any_eye(scene, small_scroll_pack, w, h, per_frame, magnifier):
    src, _, room = scene
    path = walk_path(room, 0.1).hold(0)
    path = v.CameraPath(path.position[:2], path.forward[:2], path.up[:2],
                        path.magnifier_target[:2], path.magnifier_normal[:2], path.fps)
    try:
        walk = GalleryWalk(src, small_scroll_pack, path, eye=(w, h), per_frame=per_frame,
                           magnifier=magnifier, oracle=False)
    except ValueError:
        assert not (16 <= w and 16 <= h and per_frame > 0)
        return
    s = walk.run()
    assert s["frames"] == 2

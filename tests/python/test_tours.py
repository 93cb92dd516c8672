"""Tours: the centripetal Catmull-Rom curve against an independent form of it and its known
properties, the speed and height limits, the default tour's route through a floor plan, and
the tours `gallery --tour` walks and `view` records.

References: the Hermite form with the centripetal tangents of Yuksel, Schaefer and Keyser
("Parameterization and applications of Catmull-Rom curves", 2011), computed here without the
code under test's Barry-Goldman pyramid; their result that a centripetal segment has no
self-intersection where the uniform one loops (a known case, checked with shapely); the
floor plan's own polygon for "never through a wall"."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from gigascroll.cli import main
from gigascroll.exhibit import ExhibitionError
from gigascroll.exhibit.tours import (Tour, catmull_rom, check_limits, default_tour, load_tour,
                                      tour_path, tour_samples)


def hermite_reference(p0, p1, p2, p3, s, alpha=0.5):
    """The segment p1 -> p2 as a cubic Hermite curve with the centripetal tangents."""
    t0 = 0.0
    t1 = t0 + np.linalg.norm(p1 - p0) ** alpha
    t2 = t1 + np.linalg.norm(p2 - p1) ** alpha
    t3 = t2 + np.linalg.norm(p3 - p2) ** alpha
    m1 = (t2 - t1) * ((p1 - p0) / (t1 - t0) - (p2 - p0) / (t2 - t0) + (p2 - p1) / (t2 - t1))
    m2 = (t2 - t1) * ((p2 - p1) / (t2 - t1) - (p3 - p1) / (t3 - t1) + (p3 - p2) / (t3 - t2))
    s = np.asarray(s)[:, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * p1 + h10 * m1 + h01 * p2 + h11 * m2


def test_interior_segments_match_the_hermite_form():
    rng = np.random.default_rng(7)
    pts = rng.uniform(-3, 3, (7, 3))
    times = np.cumsum(rng.uniform(0.5, 2.0, 7))
    for i in range(1, 5):  # segments with both real neighbours
        s = np.linspace(0, 1, 33)
        got = catmull_rom(pts, times, times[i] + s * (times[i + 1] - times[i]))
        want = hermite_reference(pts[i - 1], pts[i], pts[i + 1], pts[i + 2], s)
        np.testing.assert_allclose(got, want, atol=1e-9)


def test_end_segments_use_mirrored_neighbours():
    pts = np.array([[0.0, 0, 0], [1, 0, 2], [3, 1, 2]])
    times = np.array([0.0, 1.0, 3.0])
    s = np.linspace(0, 1, 17)
    got = catmull_rom(pts, times, s)
    want = hermite_reference(2 * pts[0] - pts[1], pts[0], pts[1], pts[2], s)
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_the_curve_passes_through_the_keyframes():
    rng = np.random.default_rng(3)
    pts = rng.uniform(-5, 5, (9, 3))
    times = np.cumsum(rng.uniform(0.1, 3.0, 9))
    np.testing.assert_allclose(catmull_rom(pts, times, times), pts, atol=1e-12)


def test_centripetal_has_no_loop_where_uniform_does():
    # Two close middle points between far ones: the uniform (alpha 0) segment loops back
    # over itself; the centripetal one does not, and its speed never drops to a cusp.
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [1.1, 1.0], [2.1, 0.0]])
    t = np.arange(4.0)
    s = np.linspace(1, 2, 2001)
    uniform = catmull_rom(pts, t, s, alpha=0.0)
    centripetal = catmull_rom(pts, t, s)
    assert not LineString(uniform).is_simple
    assert LineString(centripetal).is_simple
    step = np.linalg.norm(np.diff(centripetal, axis=0), axis=1)
    assert step.min() > 0.5 * step.mean()


def test_a_collinear_evenly_timed_walk_is_uniform_motion():
    # Equal spacing in space and time: the centripetal curve is the straight line at
    # constant speed (every knot interval equal: the line itself).
    pts = np.array([[0.0, 1.6, 0.0], [1, 1.6, 0], [2, 1.6, 0], [3, 1.6, 0]])
    times = np.array([0.0, 1.0, 2.0, 3.0])
    ts = np.linspace(0, 3, 61)
    np.testing.assert_allclose(catmull_rom(pts, times, ts)[:, 0], ts, atol=1e-12)


def tour(positions, times, **kw):
    positions = np.asarray(positions, float)
    return Tour(positions, positions + [0.0, 0.0, -1.0], times, **kw)


def test_speed_limit_names_the_keyframe():
    t = tour([[0, 1.6, 0], [0.5, 1.6, 0], [5.5, 1.6, 0], [6, 1.6, 0]], [0, 1, 2, 3])
    with pytest.raises(ValueError, match=r"keyframe 1 .* faster than max_speed_mps 1"):
        check_limits(t)
    # The same keyframes with 8 s for the 5 m: within the limit.
    check_limits(tour([[0, 1.6, 0], [0.5, 1.6, 0], [5.5, 1.6, 0], [6, 1.6, 0]], [0, 1, 9, 10]))


def test_height_limit_names_the_keyframe():
    t = tour([[0, 1.6, 0], [1, 1.6, 0], [2, 2.4, 0]], [0, 2, 4])
    with pytest.raises(ValueError, match=r"keyframe 1 .* outside 1.2..2 m"):
        check_limits(t)
    check_limits(tour([[0, 1.6, 0], [1, 1.6, 0], [2, 2.4, 0]], [0, 2, 4], max_height_m=2.5))


def test_times_must_increase():
    with pytest.raises(ValueError, match="keyframe 2"):
        tour([[0, 1.6, 0], [1, 1.6, 0], [2, 1.6, 0]], [0, 2, 2])


L_ROOM = [[0, 0], [8, 0], [8, 3], [3, 3], [3, 8], [0, 8]]  # an L: the corner hides one arm


def test_default_tour_walks_around_the_corner(tmp_path):
    from gigascroll.exhibit import load_exhibition
    from gigascroll.exhibit.floor_plan import build_room
    from PIL import Image
    Image.fromarray(np.full((30, 40, 3), 200, np.uint8)).save(tmp_path / "p.png")
    # One painting at the far end of each arm: the straight line between their look-at
    # points cuts through the L's corner walls.
    (tmp_path / "l.toml").write_text(f"""
[room]
walls = {L_ROOM}
height_m = 3.0
[[paintings]]
title = "East"
image = "p.png"
width_cm = 40
height_cm = 30
hang = {{ wall = 1, along_m = 1.5 }}
[[paintings]]
title = "North"
image = "p.png"
width_cm = 40
height_cm = 30
hang = {{ wall = 4, along_m = 1.5 }}
""")
    ex = load_exhibition(tmp_path / "l.toml")
    room = build_room(ex)
    t = default_tour(room, ex)
    check_limits(t)
    _, pos, _ = tour_samples(t)
    floor = Polygon(L_ROOM)
    straight = LineString([t.position[0][[0, 2]], t.position[-1][[0, 2]]])
    assert not floor.contains(straight)  # the direct way is through a wall
    path = LineString(pos[:, [0, 2]])
    assert floor.contains(path)
    clearance = min(floor.exterior.distance(Point(p)) for p in pos[:, [0, 2]])
    assert clearance > 0.3
    # It stands at each painting's look-at point, looking at the painting's centre.
    for slot in room.paintings[:2]:
        centre = np.array(slot.origin) + np.array(slot.u_axis) * slot.width_m / 2 \
            + np.array(slot.v_axis) * slot.height_m / 2
        assert any(np.allclose(tg, centre) for tg in t.target)
    cam = tour_path(t)
    assert len(cam) == int(np.floor(t.time[-1] * t.fps)) + 1
    # While walking the head looks where it goes (within 60 degrees of its velocity: a
    # target interpolated from the painting behind to the next one ahead had it walk
    # backwards for a fifth of the way), and the view turns smoothly.
    v = np.diff(cam.position, axis=0) * cam.fps
    speed = np.linalg.norm(v, axis=1)
    f = cam.forward / np.linalg.norm(cam.forward, axis=1, keepdims=True)
    moving = speed > 0.1
    assert moving.sum() > 30
    assert (np.sum(f[:-1][moving] * v[moving], axis=1) / speed[moving]).min() > 0.5
    turn = np.degrees(np.arccos(np.clip(np.sum(f[1:] * f[:-1], axis=1), -1, 1)))
    assert turn.max() < 10.0


def test_tour_file_errors_name_the_key(tmp_path, capsys):
    f = tmp_path / "t.json"
    f.write_text(json.dumps({"keyframes": [{"position": [0, 1.6, 0], "target": [0, 1.6, -1],
                                            "time": 0}, {"position": [0, 1.6], "target": [0, 1, 0],
                                                         "time": 1}]}))
    with pytest.raises(ExhibitionError, match=r"keyframes\[1\].position: expected at least 3"):
        load_tour(f)
    f.write_text("{")
    with pytest.raises(ExhibitionError, match="not a JSON tour file"):
        load_tour(f)


def test_gallery_walks_a_tour_file(tmp_path, capsys):
    from gallery_checks import gradient_pack
    pack = gradient_pack(tmp_path / "g.pack", size=(256, 128))
    f = tmp_path / "t.json"
    f.write_text(json.dumps({"fps": 10, "keyframes": [
        {"position": [0.5, 1.5, 1.5], "target": [0.5, 1.5, 0], "time": 0},
        {"position": [1.0, 1.5, 1.5], "target": [1.0, 1.5, 0], "time": 1}]}))
    out = tmp_path / "walk"
    code = main(["gallery", str(pack.path), "--room", "scroll", "--tour", str(f), "--eye",
                 "32x32", "--no-video", "--no-oracle", "--photons", "2000", "--lighting", "full",
                 "--out", str(out)])
    assert code == 0
    results = json.loads((out / "results.json").read_text())
    assert results["summary"]["frames"] == 11
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"keyframes": [
        {"position": [0, 1.5, 1], "target": [0, 1.5, 0], "time": 0},
        {"position": [9, 1.5, 1], "target": [9, 1.5, 0], "time": 1}]}))
    capsys.readouterr()
    assert main(["gallery", str(pack.path), "--tour", str(bad), "--eye", "32x32",
                 "--out", str(tmp_path / "w2")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "keyframe 0" in err[0] and "faster" in err[0]


def test_view_records_a_tour(tmp_path):
    # The viewer's recording (T) without a window: its methods on a stand-in viewer.
    from gigascroll.commands.view import Viewer
    v = SimpleNamespace(recording=None, tours=0, position=np.array([1.0, 1.6, 2.0]),
                        args=SimpleNamespace(record_tour=str(tmp_path / "tour-{n}.json")))
    v.forward = lambda: np.array([0.0, 0.0, -1.0])
    Viewer.toggle_recording(v)
    for k in range(4):
        v.record_start -= 0.3  # 0.3 s pass between frames
        v.position = v.position + [0.1, 0.0, 0.0]
        Viewer.record_keyframe(v)
    Viewer.toggle_recording(v)
    t = load_tour(tmp_path / "tour-0.json")
    assert len(t.time) == 4
    np.testing.assert_allclose(t.target - t.position, [[0, 0, -2.0]] * 4)
    check_limits(t)

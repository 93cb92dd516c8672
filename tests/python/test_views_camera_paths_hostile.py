"""Camera path files a hostile user would hand over (gigascroll.views.camera_paths): each is
a ValueError naming the problem, never a RecursionError, KeyError or a misleading message."""

import json

import numpy as np
import pytest

from gigascroll import CameraPath

GOOD = {"position": [[0, 1.6, 2]], "forward": [[0, 0, -1]], "up": [[0, 1, 0]]}


@pytest.mark.parametrize("text,message", [
    ("[" * 100000 + "]" * 100000, "nested too deeply"),
    ('{"a":' * 50000 + "1" + "}" * 50000, "nested too deeply"),
    ("[1, 2]", "expected an object"),
    (b"\xff\xfe{}", "not a camera path"),
    (json.dumps(dict(GOOD, magnifier_target=[[0, 1.6, 0]])), "magnifier_target without magnifier_normal"),
    (json.dumps(dict(GOOD, magnifier_target=[[0, 1, 0], [1, 1, 1]], magnifier_normal=[[0, 0, 1]])),
     "magnifier_target must have shape"),
    (json.dumps(dict(GOOD, up=[[0, 0, 0]])), "zero up vector"),
    (json.dumps(dict(GOOD, forward=[[0, 0, 0]])), "zero forward vector"),
    (json.dumps({"position": [[0, 0, 0]]}), "missing 'forward'"),
    (json.dumps(dict(GOOD, fps="fast")), "camera path"),
    (json.dumps(dict(GOOD, magnifier_target=[5], magnifier_normal=[[0, 0, 1]])), "wrong type"),
    # Refused when the path is made, not at the frame that reaches the pose.
    (json.dumps(dict(GOOD, position=[[1e300, 1.6, 2]])), "position of frame 0 is beyond"),
    (json.dumps(dict(GOOD, position=[[0, 1.6, 2], [0, -2e12, 2]], forward=[[0, 0, -1]] * 2,
                     up=[[0, 1, 0]] * 2)), "position of frame 1 is beyond"),
    (json.dumps(dict(GOOD, forward=[[0, 3, 0]])), "parallel at frame 0"),
    (json.dumps(dict(GOOD, forward=[[0, 0, -1e-320]])), "zero forward vector"),
    (json.dumps(dict(GOOD, magnifier_target=[[1e200, 0, 0]], magnifier_normal=[[0, 0, 1]])),
     "magnifier_target of frame 0 is beyond"),
    (json.dumps(dict(GOOD, magnifier_target=[[0, 1, 0]], magnifier_normal=[[0, 0, 0]])),
     "magnifier_normal of frame 0"),
    (json.dumps(dict(GOOD, magnifier_target=[[0, 1, 0]], magnifier_normal=[[0, None, 1]])),
     "magnifier_normal of frame 0"),
    (json.dumps(dict(GOOD, fps=1e300)), "at most 1000"),
    (json.dumps(dict(GOOD, fps=0)), "fps must be positive"),
])
def test_bad_camera_path_files(tmp_path, text, message):
    p = tmp_path / "path.json"
    (p.write_bytes if isinstance(text, bytes) else p.write_text)(text)
    with pytest.raises(ValueError, match=message):
        CameraPath.load(p)


def test_good_path_with_magnifier_round_trips(tmp_path):
    path = CameraPath(np.array(GOOD["position"], float), np.array(GOOD["forward"], float),
                      np.array(GOOD["up"], float), np.array([[0, 1.6, 0]]), np.array([[0, 0, 1.0]]))
    path.save(tmp_path / "p.json")
    back = CameraPath.load(tmp_path / "p.json")
    np.testing.assert_array_equal(back.magnifier_normal, path.magnifier_normal)


def test_huge_and_tiny_direction_vectors_give_the_unit_ones_cameras():
    """Directions are directions: forward and up of 1e300 or 1e-300 give the same cameras as
    unit ones (no overflow to NaN in the right vector)."""
    from gigascroll.views.camera_paths import frame_cameras
    n = np.array([[0, 0, 1.0]])
    unit = CameraPath(np.array([[0, 1.6, 2.0]]), np.array([[0.6, 0, -0.8]]), np.array([[0, 1.0, 0]]),
                      np.array([[0, 1.6, 0]]), n)
    for scale in (1e300, 1e-300):
        scaled = CameraPath(unit.position, unit.forward * scale, unit.up * scale,
                            unit.magnifier_target, n * scale)
        for (a, _, _), (b, _, _) in zip(frame_cameras(unit, 0), frame_cameras(scaled, 0)):
            np.testing.assert_allclose(b.position, a.position, rtol=0, atol=1e-12)
            np.testing.assert_allclose(b.forward, a.forward, rtol=0, atol=1e-12)
            np.testing.assert_allclose(b.right, a.right, rtol=0, atol=1e-12)


@pytest.mark.parametrize("up,message", [((0, 0, 0), "up vector is zero"),
                                        ((0, 0, -5), "parallel"), ((0, float("nan"), 1), "finite")])
def test_camera_up_messages_say_what_is_wrong(up, message):
    from gigascroll import Camera
    with pytest.raises(ValueError, match=message):
        Camera((0, 0, 0), (0, 0, -1), up)

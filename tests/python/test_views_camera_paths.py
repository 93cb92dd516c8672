"""Camera paths (gigascroll.views.camera_paths): constant speed, loops, the stop, JSON round
trips, and bad paths rejected."""

import numpy as np
import pytest

from gigascroll import views as v


def test_camera_paths_are_shared_data(tmp_path):
    path = v.scroll_path(duration=1.0, stop_frames=20, loops=2)
    assert len(path) == 2 * 90 + 20
    step = np.diff(path.position[:90, 0])
    np.testing.assert_allclose(step, 1.0 / 90)  # constant 1 m/s at 90 Hz
    assert np.all(path.position[-20:] == path.position[-1])  # the stop
    assert path.position[90, 0] == path.position[0, 0]  # loop back to the start
    path.save(tmp_path / "p.json")
    back = v.CameraPath.load(tmp_path / "p.json")
    np.testing.assert_array_equal(back.position, path.position)
    np.testing.assert_array_equal(back.magnifier_target, path.magnifier_target)


def test_bad_camera_paths_are_rejected(tmp_path):
    pos = np.zeros((3, 3))
    pos[1, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        v.CameraPath(pos, np.tile([0, 0, 1.0], (3, 1)), np.tile([0, 1.0, 0], (3, 1)))
    with pytest.raises(ValueError):
        v.scroll_path(speed=float("nan"))
    with pytest.raises(ValueError, match="runs off"):
        v.scroll_path(duration=20.0)
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(ValueError):
        v.CameraPath.load(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="NaN"):
        v.Camera((0, 0, float("nan")), (0, 0, 1), (0, 1, 0), 1, 1, 8, 8)

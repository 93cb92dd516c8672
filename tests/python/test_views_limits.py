"""The views' entry checks: a camera on a box corner sees past it, scene extents and feedback
sizes out of range give a ValueError."""
import numpy as np
import pytest

from gigascroll import _core
from gigascroll import views as v


def _scene():
    s = v.ExhibitionScene()
    s.add_box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    # A painting 3 m in front of the box's corner (1, 1, 1), facing it.
    s.add_painting(0, v.PaintingGeometry(512, 512), (0.0, 0.0, 4.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 2.0, 2.0)
    s.commit()
    return s


def _painting_share(scene, position):
    cam = _core.Camera(list(position), [0.5, 0.5, 4.0], [0.0, 1.0, 0.0], 40.0, (32, 32))
    keys = _core.render_view(scene, cam, 32, 32, display=False)["keys"]
    return float(np.mean(keys != v.NO_REQUEST))


def test_camera_on_a_box_corner_sees_the_painting():
    """Reference: the same view from 1 mm off the corner (outside the box)."""
    scene = _scene()
    on = _painting_share(scene, (1.0, 1.0, 1.0))
    off = _painting_share(scene, (1.001, 1.001, 1.001))
    assert off > 0.3
    assert on == pytest.approx(off, abs=0.05)


def test_scene_extents_and_feedback_sizes_are_bounded():
    s = v.ExhibitionScene()
    with pytest.raises(ValueError, match="within \\+-1e12"):
        s.add_box((0.0, 0.0, 0.0), (1e13, 1.0, 1.0))
    with pytest.raises(ValueError, match="within \\+-1e12"):
        s.add_painting(0, v.PaintingGeometry(64, 64), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1e300, 1.0)
    scene = _scene()
    cam = _core.Camera([1.0, 1.0, 1.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 0.5, 0.5, 8, 8)
    with pytest.raises(ValueError, match="feedback pass would need"):
        _core.render_view(scene, cam, 65535, 65535)

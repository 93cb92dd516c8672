"""The feedback-free baselines (gigascroll.views.baselines): Ma VT's per-tile test against the
ray-cast feedback (the brute-force reference of what the view needs), LOD-texture's LOD bands
and memory."""

import numpy as np
import pytest

from gigascroll import views as v
from gigascroll.views import baselines as b


@pytest.fixture(scope="module")
def scene(small_scroll):
    """The small painting on the wall (conftest)."""
    return small_scroll


def _feedback_requests(ex, path):
    bufs = v.feedback_buffers(ex, path, 0, magnifier=None)
    flat = np.concatenate([x.ravel() for x in bufs])
    return np.unique(flat[flat != v.NO_REQUEST])


@pytest.mark.parametrize("distance", [0.12, 0.25, 0.45])
def test_ma_vt_covers_what_the_view_needs(scene, distance):
    path = v.scroll_path(distance=distance, speed=0.0, duration=0.01, start_x=0.4,
                         exhibition=scene, magnifier=False)
    need = _feedback_requests(scene, path)
    ma = b.MaVT(scene).requests(path, 0)
    assert need.size > 0
    # Every tile the rays see is requested, at the level the rays ask (head-on painting).
    assert np.isin(need, ma).all()
    # ... and not much more: the whole painting is never requested at the fine level.
    assert ma.size < 2 * need.size + 40


def test_ma_vt_tests_every_level0_tile(scene):
    t = scene.tiles[0]
    assert b.MaVT(scene).tile_total == t.tiles_x(0) * t.tiles_y(0)
    # Looking away from the painting: nothing requested.
    path = v.CameraPath(np.array([[0.5, 1.5, -0.3]]), np.array([[0.0, 0.0, -1.0]]),
                        np.array([[0.0, 1.0, 0.0]]))
    assert b.MaVT(scene).requests(path, 0).size == 0


def test_lod_mapping_bands_levels_and_memory(scene):
    lod = b.LodMapping(scene)
    levels = scene.tiles[0].levels
    e0 = b.LOD_BANDS_M[0]
    assert b.LOD_BANDS_M == pytest.approx((e0, 2 * e0, 3 * e0, 5 * e0))
    assert [lod.level_of(d, levels) for d in (0.05, 0.2, 0.4, 0.6, 5.0)] == \
        [0, 1, 2, 3, levels - 1]
    # The first bands agree with the rays' level for a head-on view.
    for distance, level in ((0.1, 0), (0.25, 1)):
        path = v.scroll_path(distance=distance, speed=0.0, duration=0.01, start_x=0.4,
                             exhibition=scene, magnifier=False)
        need_levels = set(v.unpack_requests(_feedback_requests(scene, path))[1].tolist())
        assert need_levels == {level}
        assert lod.chosen_levels(path, 0) == [level]
        keys = lod.requests(path, 0)
        t = scene.tiles[0]
        assert keys.size == len(np.unique(keys)) == t.tile_count(level)
        assert lod.memory_bytes(path, 0, 128 * 128 * 4) == t.tile_count(level) * 65536


def test_baseline_errors(scene):
    with pytest.raises(ValueError, match="baseline"):
        b.make_baseline("oracle", scene)
    with pytest.raises(ValueError, match="bands"):
        b.LodMapping(scene, bands=(0.2, 0.1))
    with pytest.raises(ValueError, match="bands"):
        b.LodMapping(scene, bands=(float("nan"),))

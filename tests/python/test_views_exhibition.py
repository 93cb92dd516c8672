"""The exhibition (gigascroll.views.exhibition): the tables room of 8 to 40 paintings with its
routes in view, and scenes that cannot be built."""

import numpy as np
import pytest

from gigascroll import views as v


def test_rooms_of_8_to_40_paintings_and_their_routes():
    for n in (8, 16, 24, 32, 40):
        ex = v.multi_exhibition(n)
        route = v.multi_route(n, duration=0.1)
        assert ex.scene.painting_count == n and ex.scene.box_count == 5 * n // 8 + 1
        assert route.position[0, 1] == pytest.approx(1.70)
        bufs = v.feedback_buffers(ex, route, 0)
        seen = np.unique(v.unpack_requests(np.concatenate([b.ravel() for b in bufs])
                                           [np.concatenate([b.ravel() for b in bufs])
                                            != v.NO_REQUEST])[0])
        assert seen.size >= 8  # the first table's paintings are in view


def test_bad_exhibitions_are_rejected():
    with pytest.raises(ValueError, match="multiple of 8"):
        v.multi_exhibition(12)
    scene = v.ExhibitionScene()
    with pytest.raises(ValueError, match="orthonormal"):
        scene.add_painting(0, v.PaintingGeometry(100, 100), (0, 0, 0), (1, 0, 0), (1, 0, 0), 1, 1)

"""Fuzz: bake(hot_spots=...) refuses what is not 0 or a number in [1, 1e6] with a ValueError
(before any work), and bakes finite, non-negative light otherwise."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gigascroll as g
from gigascroll.gallery import Gallery

from gallery_checks import box_room, uniform_pack

FUZZ = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def lit(tmp_path_factory):
    pack = uniform_pack(tmp_path_factory.mktemp("fuzzhot") / "u.pack", {"red": (200, 60, 40)})
    gal = Gallery.from_room(box_room(), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=2000)
    return gal, vt


@FUZZ
@given(hot_spots=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 40),
                           st.sampled_from([1 << 40, 1e6, 1e6 + 1, 0.999]), st.booleans(), st.none(),
                           st.text(max_size=3)))
def test_hot_spots_refused_or_finite_light(lit, hot_spots):
    gal, vt = lit
    valid = isinstance(hot_spots, (int, float)) and not isinstance(hot_spots, bool) \
        and math.isfinite(hot_spots) and (hot_spots == 0 or 1 <= hot_spots <= 1e6)
    if not valid:
        with pytest.raises(ValueError, match="hot_spots"):
            gal.bake(spacing=0.5, light_samples=2, final_gather=4, hot_spots=hot_spots)
        return
    gal.bake(spacing=0.5, light_samples=2, final_gather=4, hot_spots=hot_spots)
    img = gal.render_display(gal.camera((6, 4)), vt, lighting="baked")
    assert np.isfinite(img).all() and (img >= 0).all() and img.max() > 0

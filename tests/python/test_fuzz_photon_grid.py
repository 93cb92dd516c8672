"""Fuzz cases for the adaptive photon grid (PhotonMap(grid='adaptive')): random clouds, radii
and offsets find exactly numpy's brute-force set; hostile input raises ValueError. Also the
progressive render's coarse_passes option."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import gigascroll as g



@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(n=st.integers(0, 400), seed=st.integers(0, 2**32 - 1),
       radius=st.floats(1e-4, 10.0), offset=st.sampled_from([0.0, 1e3, -3e4]),
       spread=st.sampled_from([1e-3, 1.0, 100.0]))
def test_adaptive_grid_matches_brute_force(n, seed, radius, offset, spread):
    rng = np.random.default_rng(seed)
    pts = (rng.random((n, 3)) * spread + offset).astype(np.float32)
    if n > 4:
        pts[: n // 4] = pts[0]  # duplicates
    pm = g.PhotonMap(pts, radius, grid="adaptive")
    queries = (rng.random((8, 3)) * spread * 1.2 + offset - 0.1 * spread).astype(np.float32)
    if n:
        queries[:4] = pts[rng.integers(0, n, 4)]
    for q in queries:
        d = pts - q
        d2 = (d * d).sum(axis=1, dtype=np.float32)  # float32 like the gathers (no FMA)
        ref = sorted(map(tuple, pts[d2 <= np.float32(radius) ** 2]))
        assert sorted(map(tuple, pm.query_radius(q, radius))) == ref


@pytest.mark.parametrize("pts, radius", [
    (np.array([[0, 0, np.nan]], np.float32), 0.1),
    (np.array([[0, 0, np.inf]], np.float32), 0.1),
    (np.array([[3e38, 0, 0], [-3e38, 0, 0]], np.float32), 0.1),
    (np.zeros((4, 3), np.float32), 0.0),
    (np.zeros((4, 3), np.float32), -1.0),
    (np.zeros((4, 3), np.float32), float("nan")),
    (np.zeros((4, 2), np.float32), 0.1),
])
def test_adaptive_grid_rejects_hostile_input(pts, radius):
    with pytest.raises(ValueError):
        g.PhotonMap(pts, radius, grid="adaptive")


def test_adaptive_grid_rejects_queries_beyond_its_radius():
    pm = g.PhotonMap(np.zeros((4, 3), np.float32), 0.1, grid="adaptive")
    with pytest.raises(ValueError, match="radius"):
        pm.query_radius(np.zeros(3, np.float32), 0.2)
    assert len(pm.query_radius(np.float32([np.nan, 0, 0]), 0.1)) == 0


_CORNELL16 = g.builtin_scene("cornell", resolution=(16, 16))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(coarse=st.one_of(st.integers(-2**40, 2**40), st.floats(allow_nan=True), st.booleans(), st.none(),
                        st.text(max_size=3)))
def test_progressive_coarse_passes_is_validated(coarse):
    """render(progressive=True, coarse_passes=...): an integer in [0, 2^24] renders a finite
    image (the same disc as the fine one beyond the passes it names); anything else is a
    ValueError, never a crash."""
    scene, cam = _CORNELL16
    kw = dict(photons=500, radius=0.05, progressive=True, passes=2, coarse_passes=coarse)
    if isinstance(coarse, int) and not isinstance(coarse, bool) and 0 <= coarse <= 1 << 24:
        img = g.render(scene, cam, **kw)
        assert np.isfinite(img).all()
        if coarse >= 2:  # every pass coarse either way
            assert np.array_equal(img, g.render(scene, cam, **(kw | dict(coarse_passes=2))))
    else:
        with pytest.raises(ValueError, match="coarse_passes"):
            g.render(scene, cam, **kw)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(final=st.one_of(st.booleans(), st.integers(-3, 3), st.floats(allow_nan=True), st.none(),
                       st.text(max_size=3)),
       progressive=st.booleans())
def test_final_gather_is_validated(final, progressive):
    """render(final_gather=...): a bool renders a finite, non-negative image; anything else
    (1, "yes", None, NaN) is a ValueError naming the option, never a crash."""
    scene, cam = _CORNELL16
    kw = dict(photons=500, radius=0.05, progressive=progressive, passes=2, final_gather=final)
    if not progressive:
        kw.pop("passes")
    try:
        img = g.render(scene, cam, **kw)
    except ValueError as e:
        assert not isinstance(final, bool) or (final and not progressive), e
        assert "final_gather" in str(e)
        return
    assert isinstance(final, bool)
    assert np.isfinite(img).all() and (img >= 0).all()

"""Independent seeds: the photon mapper's random numbers come from a counter-based generator
keyed by the seed, so neighbouring seeds are independent runs and error bars averaged over
seeds 0..n-1 are honest."""

from __future__ import annotations

import math

import numpy as np

import gigascroll as g


def _photon_set(ph) -> set:
    return set(map(tuple, ph["position"].tolist()))


def test_neighbouring_seeds_share_no_photons():
    scene, _ = g.builtin_scene("cornell", resolution=(8, 8))
    a, b = (_photon_set(g.trace_photons(scene, 20_000, seed=s)) for s in (0, 1))
    assert len(a) > 10_000
    # Continuous positions of independent photon sets coincide with probability ~0.
    assert len(a & b) == 0


def test_furnace_spread_over_neighbouring_seeds_is_that_of_independent_runs():
    """The photon-map part of the furnace image (no light sampling), over seeds 0..15 and over
    16 seeds far apart: the same spread. With seeds derived by hash_combine(seed, i) the
    neighbouring seeds replayed each other's photons and their spread was 0.28 of the
    independent one; an F(15, 15) ratio of variances below 0.3 has probability < 1%."""
    scene, cam = g.builtin_scene("furnace", resolution=(16, 16), albedo=0.5, emission=1.0)

    def means(seeds):
        return np.array([g.render(scene, cam, photons=20_000, radius=0.05, seed=s, direct=False).mean()
                         for s in seeds])

    near, far = means(range(16)), means(7919 * (s + 1) for s in range(16))
    ratio = near.var(ddof=1) / far.var(ddof=1)
    assert 0.3 < ratio < 1 / 0.3, ratio
    # And the error bar from the neighbouring seeds covers the exact answer: the photon-map
    # part is Le + rho^2 Le / (1 - rho), plus the tessellation's share (0.5%).
    exact = 1.0 + 0.25 / 0.5
    stderr = near.std(ddof=1) / math.sqrt(len(near))
    assert abs(near.mean() - exact) < 4 * stderr + 0.005 * exact, (near.mean(), stderr, exact)

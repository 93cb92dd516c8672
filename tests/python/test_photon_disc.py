"""Bias near edges and thin walls, sphere gather against the surface disc, measured against
Mitsuba's cached references in the test rooms (regions from each pixel's primary hit)."""

from __future__ import annotations

import numpy as np
import pytest

import gigascroll as g
from test_photon_rooms import SIZE, room_reference


def _hit_points(scene, cam) -> np.ndarray:
    pts = np.full((SIZE, SIZE, 3), np.nan)
    for y in range(SIZE):
        for x in range(SIZE):
            hit = scene.intersect(list(cam.position), list(cam.direction(x + 0.5, y + 0.5)))
            if hit is not None:
                pts[y, x] = hit[1]
    return pts


def _regions(name: str, pts: np.ndarray) -> dict[str, np.ndarray]:
    x, y, z = pts[..., 0], pts[..., 1], pts[..., 2]
    if name == "room_partition":  # the dark side's floor along the partition, away from the slit
        return {"leak": (np.abs(y) < 1e-3) & (x > 0.01) & (x < 0.11) & (np.abs(z) > 0.25)}
    # Within 10 cm of a room edge: on a wall, floor or ceiling and near a second one.
    d = np.sort(np.stack([np.abs(x + 2), np.abs(x - 2), np.abs(y), np.abs(y - 2.6), np.abs(z + 2),
                          np.abs(z - 2)], -1), -1)
    out = {"edge": (d[..., 0] < 1e-3) & (d[..., 1] < 0.1)}
    if name == "room_lit":  # the painting's front (z = -1.97, |x| < 0.6, |y - 1.4| < 0.4)
        inside = (np.abs(x) < 0.6) & (np.abs(y - 1.4) < 0.4)
        rim = (0.6 - np.abs(x) < 0.05) | (0.4 - np.abs(y - 1.4) < 0.05)
        out["painting border"] = (np.abs(z + 1.97) < 1e-3) & inside & rim  # its 5 cm border
        outside = np.hypot(np.maximum(np.abs(x) - 0.6, 0), np.maximum(np.abs(y - 1.4) - 0.4, 0))
        out["wall around the painting"] = (np.abs(z + 2) < 1e-3) & ~inside & (outside < 0.1)  # within 10 cm
    return out


# |bias| bounds of the disc per region, at seed 0. Measured there: edges -0.3% (lit), -0.1%
# (indirect); the partition's leak +0.6%; the painting's border +1.4% and the wall around it
# -1.8% (mean of seeds 0-3: +1.7% and -0.8%; +2.1% and -0.6% with sector ends bisected to r / 16
# instead of r / 64; -2.9% and -3.0% with the first disc of 8 sectors without bisection or
# overhang probes). With the camera samples of spp > 1 on one stratified pattern for the image
# (straight light edges): the border +2.01%, +2.0% and +1.8% at seeds 0, 3, 2 and -1.6% at
# seed 1 (mean +1.1%): the bound leaves room for the seed's spread.
DISC_BOUNDS = {"edge": 0.01, "leak": 0.01, "painting border": 0.025, "wall around the painting": 0.02}


@pytest.fixture(scope="module", params=g.ROOMS)
def region_bias(request):
    """Relative bias of each region's summed radiance, sphere and disc, 2^20 photons, 64 spp."""
    name = request.param
    scene, cam = g.builtin_scene(name, resolution=(SIZE, SIZE))
    ref = room_reference(name)
    masks = _regions(name, _hit_points(scene, cam))
    assert all(m.sum() > 10 for m in masks.values()), {k: int(m.sum()) for k, m in masks.items()}
    out = {}
    for disc in (False, True):
        img = g.render(scene, cam, photons=1 << 20, spp=64, disc=disc)
        out[disc] = {k: float(img[m].sum() / ref[m].sum() - 1) for k, m in masks.items()}
    return name, out


def test_surface_disc_removes_edge_and_leak_bias(region_bias):
    """Measured at the default radius: sphere -7.9% / -10.1% at the lit and indirect rooms'
    edges, +29% leak along the partition's floor and +5% on the painting's border."""
    name, bias = region_bias
    if name == "room_partition":
        assert bias[False]["leak"] > 0.15, bias  # the sphere leaks the lit side's floor photons
    else:
        assert bias[False]["edge"] < -0.05, bias  # the sphere darkens edges
    for region, b in bias[True].items():
        assert abs(b) < DISC_BOUNDS[region], (name, region, bias)


def test_disc_rejects_incompatible_options():
    scene, cam = g.builtin_scene("cornell", resolution=(8, 8))
    for kw in (dict(gather="knn"), dict(kernel="cone"), dict(pipeline="two-pass", cooperative=True, grid="hash")):
        with pytest.raises(ValueError, match="disc"):
            g.render(scene, cam, photons=1000, radius=0.05, disc=True, **kw)


def test_disc_pipelines_agree_and_progressive_runs():
    scene, cam = g.builtin_scene("room_lit", resolution=(16, 16))
    a = g.render(scene, cam, photons=20_000, spp=2, disc=True)
    b = g.render(scene, cam, photons=20_000, spp=2, disc=True, pipeline="two-pass")
    assert np.allclose(a, b, rtol=1e-5, atol=1e-6)
    p = g.render(scene, cam, photons=20_000, progressive=True, passes=4, disc=True)
    assert np.isfinite(p).all() and p.mean() > 0
    # The disc is the default of progressive and one-shot renders; disc=False is the sphere.
    assert np.array_equal(p, g.render(scene, cam, photons=20_000, progressive=True, passes=4))
    assert np.array_equal(a, g.render(scene, cam, photons=20_000, spp=2))
    assert not np.array_equal(a, g.render(scene, cam, photons=20_000, spp=2, disc=False))


def test_disc_with_a_huge_radius_gives_a_finite_image():
    """Probe rays are kept within the scene's diagonal (Embree rejects rays beyond ~1e18)."""
    scene, cam = g.builtin_scene("cornell", resolution=(8, 8))
    for progressive in (False, True):
        img = g.render(scene, cam, photons=1000, radius=1e30, disc=True, progressive=progressive, passes=2)
        assert np.isfinite(img).all()

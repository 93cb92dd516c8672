"""The photon tracer without a bounce cap (furnace at albedo up to 0.99), its memory budget, and
the renderer's entry checks: rays, cameras and image sizes out of range give a ValueError, a
camera standing on a mesh vertex sees the room."""
import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll import _core


@pytest.mark.parametrize("rho", [0.5, 0.9, 0.99])
def test_furnace_stored_energy_has_no_bounce_cap(rho):
    """Closed sphere of albedo rho: the stored flux is phi * rho / (1 - rho) (every bounce after
    the first stores the photon with its power, Russian roulette keeps it unbiased). A cap of 256
    bounces loses phi * rho^256 / (1 - rho) of it: 7.7% at rho = 0.99, over 5 sigma here."""
    n = {0.5: 100_000, 0.9: 50_000, 0.99: 20_000}[rho]
    scene, _ = g.builtin_scene("furnace", albedo=rho, emission=1.0)
    ph = _core._trace_photons(scene, n, seed=5)
    phi = np.array(ph["emitted_power"], dtype=np.float64)
    stored = ph["power"].astype(np.float64).sum(axis=0)
    expected = phi * rho / (1 - rho)
    sigma = phi / math.sqrt(n) * math.sqrt(rho) / (1 - rho)  # geometric number of copies
    assert np.all(np.abs(stored - expected) < 5 * sigma), (stored, expected, sigma)
    # The count of stored photons is itself geometric: mean n * rho / (1 - rho).
    mean_count = n * rho / (1 - rho)
    assert abs(ph["stored"] - mean_count) < 5 * math.sqrt(n * rho) / (1 - rho)
    if rho == 0.99:
        truncated = phi * (rho - rho ** 256) / (1 - rho)  # what the old 256-bounce cap stored
        assert np.all(np.abs(stored - truncated) > 5 * sigma)


def test_furnace_render_at_albedo_099():
    """The rendered radiance is Le / (1 - rho) = 100 at rho = 0.99 (the capped tracer gave ~93)."""
    rho = 0.99
    scene, camera = g.builtin_scene("furnace", resolution=(12, 12), albedo=rho, emission=1.0)
    img = g.render(scene, camera, photons=20_000, radius=0.1, seed=2)
    # Tessellation (96 x 48 facets) and the gather's bias are well under 2% (test_photon.py).
    assert img.mean() == pytest.approx(1 / (1 - rho), rel=0.03)


def test_photon_budget_names_the_memory():
    """Albedo 0.999 stores ~1000 photons per emitted one: past the budget a ValueError that
    names the memory, not gigabytes of photons or a silently truncated estimate."""
    scene, _ = g.builtin_scene("furnace", albedo=0.999, emission=1.0)
    with pytest.raises(ValueError, match=r"photons stored \(.*MiB, the memory budget\)"):
        _core._trace_photons(scene, 2000, max_stored=100_000)
    ok = _core._trace_photons(scene, 20, max_stored=100_000)  # under the budget: all of it
    assert 0 < ok["stored"] <= 100_000


def test_photon_counts_and_threads_are_bounded():
    scene, camera = g.builtin_scene("furnace", resolution=(4, 4), albedo=0.5)
    with pytest.raises(ValueError, match="2\\^32 photons"):
        _core._trace_photons(scene, 1 << 40)
    with pytest.raises(ValueError, match="threads must be at most 1024"):
        _core._trace_photons(scene, 100, threads=1 << 20)
    with pytest.raises(ValueError, match="threads must be at most 1024"):
        g.render(scene, camera, photons=100, threads=5000)
    big = g.Camera([0, 0, 0], [0, 0, 1], [0, 1, 0], 45, resolution=(65536, 65536))
    with pytest.raises(ValueError, match=r"would need 48\.0 GiB"):
        g.render(scene, big, photons=100)


def _cornell():
    return g.builtin_scene("cornell", resolution=(16, 16))


def test_camera_on_a_mesh_vertex_sees_the_room():
    """A camera exactly on the box's corner (1, 1, 1) used to hit the corner's own triangles
    at t ~ 1e-8 and render black. The reference is the same view from 1e-3 inside the box."""
    scene, _ = _cornell()
    on = g.Camera([1, 1, 1], [0, 0, 0], [0, 1, 0], 60, resolution=(16, 16))
    near = g.Camera([0.999, 0.999, 0.999], [0, 0, 0], [0, 1, 0], 60, resolution=(16, 16))
    a = g.render(scene, on, photons=20_000, seed=1)
    b = g.render(scene, near, photons=20_000, seed=1)
    assert (a.sum(axis=2) > 0).mean() > 0.95
    assert a.mean() == pytest.approx(b.mean(), rel=0.05)


@pytest.mark.parametrize("origin,direction", [
    ((0, 0, 0), (math.nan, 0, 1)), ((0, 0, 0), (0, 0, math.inf)), ((1e30, 0, 0), (0, 0, 1)),
    ((0, 0, 0), (0, 0, 0)), ((0, 0, 0), (0, 0, 1e20)), ((math.nan, 0, 0), (0, 0, 1)),
])
def test_intersect_rejects_rays_embree_would_abort_on(origin, direction):
    scene, _ = _cornell()
    with pytest.raises(ValueError, match="Scene.intersect: ray"):
        scene.intersect(origin, direction)
    hit = scene.intersect((-0.9, 0, 0.5), (-1, 0, 0))  # a valid ray still hits the left wall
    assert hit is not None and hit[0] == pytest.approx(0.1, abs=1e-5)


def test_cameras_and_scenes_are_bounded_where_they_enter():
    with pytest.raises(ValueError, match=r"camera: position must be finite \(no NaN or Inf\) and within"):
        g.Camera([1e20, 0, 0], [0, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="camera: up vector is zero"):
        g.Camera([0, 0, 3], [0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="camera up vector is zero"):
        _core.Camera([0, 0, 3], [0, 0, -1], [0, 0, 0], 1.0, 1.0, 8, 8)
    with pytest.raises(ValueError, match="field of view"):
        _core.Camera([0, 0, 3], [0, 0, -1], [0, 1, 0], 1e300, 1.0, 8, 8)
    huge_up = g.Camera([0, 0, 3], [0, 0, 0], [0, 1e300, 0])  # direction only: accepted
    assert huge_up.up == pytest.approx([0, 1, 0])
    _, cam = _cornell()
    with pytest.raises(ValueError, match="StereoCamera: the right eye"):
        g.StereoCamera(cam, 1e300)
    scene = g.Scene()
    with pytest.raises(ValueError, match="beyond \\+-1e12"):
        scene.add_mesh(np.array([[0, 0, 0], [1e15, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))

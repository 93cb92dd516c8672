"""Checks shared by the tests that compare a scene of ours with the same scene in Mitsuba 3."""

import numpy as np
import pytest


def assert_rays_match_mitsuba(mi, mscene, scene, camera, size: int, rng, rel: float = 1e-5,
                              rays: int = 200) -> None:
    """Rays from Mitsuba's own sensor have our camera's directions and hit our scene at the
    same distances: the sensor convention and the geometry agree."""
    sensor = mscene.sensors()[0]
    for u, v in rng.random((rays, 2)):
        ray, _ = sensor.sample_ray(0.0, 0.0, mi.Point2f(u, v), mi.Point2f(0.5, 0.5))
        assert np.allclose(camera.direction(u * size, v * size), np.array(ray.d), atol=1e-5)
        si = mscene.ray_intersect(ray)
        hit = scene.intersect(list(ray.o), list(ray.d))
        assert (hit is None) == (not si.is_valid())
        if hit is not None:
            assert hit[0] == pytest.approx(float(si.t), rel=rel)

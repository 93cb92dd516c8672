"""The demo's Cornell box (`gigascroll demo`, DEMO_CORNELL) as a person looks at it: no
salt-and-pepper on the tall block's front or the floor, and straight edges on the light.

Salt-and-pepper: the share of pixels whose luminance differs from the median of their 3 x 3
neighbourhood by more than a fraction of it, on the flat faces (tall block front, floor; two
pixels in from their outlines, found by casting the pixels' rays). A render with four times the
camera samples is the reference (its share is what the scene itself gives the metric); the old
settings (one independent emitter sample per camera sample, independent jitter) measured 42%
on the block and 12% on the floor."""

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll.commands.demo import DEMO_CORNELL

SIZE = 256  # the demo's resolution


def luminance(img):
    return np.asarray(img, np.float64) @ np.array([0.2126, 0.7152, 0.0722])


def salt_and_pepper(img, mask, fraction):
    lum = luminance(img)
    pad = np.pad(lum, 1, mode="edge")
    h, w = lum.shape
    med = np.median(np.stack([pad[i:i + h, j:j + w] for i in range(3) for j in range(3)]), axis=0)
    return float((np.abs(lum - med) > fraction * np.maximum(med, 1e-3))[mask].mean())


def erode(mask, n):
    for _ in range(n):
        p = np.pad(mask, 1)
        mask = mask & p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]
    return mask


@pytest.fixture(scope="module")
def cornell():
    """The scene, its camera and the triangle each pixel centre sees (-1: none)."""
    scene, cam = g.builtin_scene("cornell", resolution=(SIZE, SIZE))
    f, r, u, p = (np.array(a, float) for a in (cam.forward, cam.right, cam.up, cam.position))
    t = math.tan(math.radians(cam.fov) / 2)
    tri = np.full((SIZE, SIZE), -1)
    for y in range(SIZE):
        sy = (1 - 2 * (y + 0.5) / SIZE) * t
        for x in range(SIZE):
            sx = (2 * (x + 0.5) / SIZE - 1) * t
            hit = scene.intersect(p.tolist(), (f + sx * r + sy * u).tolist())
            tri[y, x] = -1 if hit is None else hit[2]
    return scene, cam, tri


def face(tri, triangles, inset=2):
    return erode(np.isin(tri, triangles), inset)


@pytest.fixture(scope="module")
def demo(cornell):
    scene, cam, _ = cornell
    return g.render(scene, cam, **DEMO_CORNELL)


def test_the_faces_are_where_the_test_looks(cornell):
    scene, _, tri = cornell
    # triangles in build order: floor 0-1, ..., the tall block's front 20-21, the light 34-35
    assert scene.triangle_count == 36
    assert face(tri, [20, 21]).sum() > 4000 and face(tri, [0, 1], 3).sum() > 4000
    assert np.isin(tri, [34, 35]).sum() > 300


def test_no_salt_and_pepper_on_the_tall_block_and_the_floor(cornell, demo):
    scene, cam, tri = cornell
    block, floor = face(tri, [20, 21]), face(tri, [0, 1], 3)
    ref = g.render(scene, cam, **{**DEMO_CORNELL, "spp": 16})
    # the metric on the reference: what the scene itself gives it
    assert salt_and_pepper(ref, block, 0.10) <= 0.002
    assert salt_and_pepper(ref, floor, 0.15) <= 0.005
    assert salt_and_pepper(demo, block, 0.10) <= 0.01   # 0.3% measured
    assert salt_and_pepper(demo, floor, 0.15) <= 0.025  # 0.6-1.2% over seeds
    # and no darkening: the faces' mean radiance is the reference's
    for m in (block, floor):
        assert luminance(demo)[m].mean() == pytest.approx(luminance(ref)[m].mean(), rel=0.01)


def test_the_old_settings_fail_the_metric(cornell):
    """The metric sees the defect: one independent emitter sample per camera sample."""
    scene, cam, tri = cornell
    old = g.render(scene, cam, **{**DEMO_CORNELL, "light_samples": 1})
    assert salt_and_pepper(old, face(tri, [20, 21]), 0.10) > 0.2


def test_the_lights_edges_are_straight(cornell, demo):
    """The light clipped to white (radiance above 1, as the PNG shows it) is a trapezoid
    whose top and bottom edges lie on one pixel row each: with independent jitter an edge
    pixel saw 0 to 4 of its samples hit the light and the bottom edge came out notched."""
    _, _, tri = cornell
    light = luminance(demo) > 1.0
    rows = np.flatnonzero(light.any(axis=1))
    cols = np.flatnonzero(light.any(axis=0))
    assert 6 <= len(rows) <= 20 and 30 <= len(cols) <= 60
    assert np.all(np.diff(rows) == 1) and np.all(np.diff(cols) == 1)
    inner = light[:, cols[3]:cols[-3] + 1]  # away from the slanted sides
    top = inner.argmax(axis=0)
    bottom = inner.shape[0] - 1 - inner[::-1].argmax(axis=0)
    assert np.all(top == top[0]) and np.all(bottom == bottom[0])
    assert np.all(inner[top[0]:bottom[0] + 1])  # no hole inside
    # the slanted sides: one edge pixel column per row at most moves, monotonically
    left = light.argmax(axis=1)[rows]
    assert np.all(np.abs(np.diff(left)) <= 1)
    # and the geometry agrees: the rows and columns the light's triangles cover at centres
    centres = np.isin(tri, [34, 35])
    assert abs(int(centres.any(axis=1).sum()) - len(rows)) <= 2


def test_stratified_emitter_samples_are_unbiased(cornell):
    """16 stratified emitter samples per camera sample against 1 independent one, direct
    light only, at equal shadow rays: the same mean radiance on each face."""
    scene, _, _ = cornell
    _, cam = g.builtin_scene("cornell", resolution=(64, 64))
    strat = g.render(scene, cam, spp=4, light_samples=16, indirect=False, photons=1)
    indep = g.render(scene, cam, spp=64, light_samples=1, indirect=False, photons=1)
    lum_s, lum_i = luminance(strat), luminance(indep)
    lit = (lum_i > 0.05) & (lum_i < 1)  # lit surfaces, not the light (its edge pixels' share
    # of it follows the camera samples' pattern, which differs with spp)
    assert lum_s[lit].mean() == pytest.approx(lum_i[lit].mean(), rel=0.01)
    # and less noise: the 3 x 3 median's residual is smaller
    assert salt_and_pepper(strat, lit, 0.05) < salt_and_pepper(indep, lit, 0.05)

"""A room far from the world's origin is lit as the same room at the origin: the gallery holds
it in coordinates around itself (Gallery.origin in the core), so float keeps its precision
where the light is computed. The reference is the same room at the origin, rendered with the
same seed: before this, full lighting lost 75% of its mean radiance at 3 km and showed
shadow-acne stripes at 9 km, while unlit images stayed the same."""

import dataclasses

import numpy as np
import pytest

from gallery_checks import box_room, uniform_pack
from gigascroll import Camera
from gigascroll.gallery import Gallery

# Along a diagonal, so that every axis but z is far (z stays around the origin).
DIRECTION = np.array([0.6, 0.8, 0.0])
SIZE = (96, 72)


def shifted(spec, offset):
    """The room moved by `offset` (metres), cameras included."""
    d = np.asarray(offset, float)
    surfaces = [dataclasses.replace(s, vertices=np.asarray(s.vertices, float) + d)
                for s in spec.surfaces]
    slots = [dataclasses.replace(p, origin=tuple(np.asarray(p.origin, float) + d))
             for p in spec.paintings]
    return dataclasses.replace(spec, surfaces=surfaces, paintings=slots,
                               camera_eye=tuple(np.asarray(spec.camera_eye, float) + d),
                               camera_target=tuple(np.asarray(spec.camera_target, float) + d))


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("far") / "pack", {"red": (200, 40, 40)})


def stills(pack, km):
    g = Gallery.from_room(shifted(box_room(), DIRECTION * km * 1000), pack)
    camera = g.camera(SIZE)
    return g, camera, {lighting: g.still(camera, lighting=lighting, photons=1 << 16, seed=1)
                       for lighting in ("unlit", "full", "baked")}


@pytest.fixture(scope="module")
def at_origin(pack):
    return stills(pack, 0)


@pytest.mark.parametrize("km", [1, 3, 9])
def test_far_room_is_lit_as_at_the_origin(pack, at_origin, km):
    _, _, reference = at_origin
    _, _, images = stills(pack, km)
    for lighting, image in images.items():
        ref = reference[lighting]
        # Mean radiance: the vertices are float at 9 km (a millimetre's step), the rest is
        # the same computation; measured within 0.08% (full) and 0.01% (baked).
        assert image.mean() == pytest.approx(ref.mean(), rel=2e-3), lighting
        # No stripes: every column's mean (shadow acne on the walls came in vertical
        # stripes) and nearly every pixel as at the origin.
        columns, ref_columns = image.mean(axis=(0, 2)), ref.mean(axis=(0, 2))
        np.testing.assert_allclose(columns, ref_columns, rtol=0.02, atol=1e-4, err_msg=lighting)
        if lighting != "full":  # full's emitter samples are seeded by position: other noise
            close = np.isclose(image, ref, rtol=0.01, atol=1e-4).all(axis=2)
            assert close.mean() > 0.98, (lighting, close.mean())


def test_origin_room_keeps_its_coordinates(at_origin):
    """A room around the origin is not moved, so its frames stay bit for bit the same."""
    g, _, _ = at_origin
    assert tuple(g.origin) == (0.0, 0.0, 0.0)
    lo, hi = g.bounds
    np.testing.assert_array_equal(lo, [-2, 0, -2])
    np.testing.assert_array_equal(hi, [2, 3, 2])


def test_world_coordinates_at_the_interface(pack, at_origin):
    """Bounds, intersect, render_view and the per-pixel hits of a far room are in the world's
    coordinates: the origin room's values plus the offset."""
    g0, camera0, _ = at_origin
    offset = DIRECTION * 9000
    g = Gallery.from_room(shifted(box_room(), offset), pack)
    camera = g.camera(SIZE)
    # x and y far: held around the room's middle (float); z spans the origin: not moved
    lo, hi = (np.array(b) for b in g.bounds)
    np.testing.assert_allclose(g.origin, [*((lo + hi) / 2)[:2], 0.0], atol=1e-3)
    for a, b in zip(g.bounds, g0.bounds):
        np.testing.assert_allclose(np.array(a) - offset, b, atol=2e-3)
    eye = np.array(box_room().camera_eye)
    hit0 = g0.intersect(tuple(eye), (0.0, -0.2, -1.0))
    hit = g.intersect(tuple(eye + offset), (0.0, -0.2, -1.0))
    assert hit[2:] == hit0[2:]  # the same triangle and painting slot
    np.testing.assert_allclose(np.array(hit[1]) - offset, hit0[1], atol=2e-3)
    keys0 = g0.render_view(camera0, width=SIZE[0], height=SIZE[1])["keys"]
    keys = g.render_view(camera, width=SIZE[0], height=SIZE[1])["keys"]
    assert (keys == keys0).mean() > 0.99


def test_far_hits_are_world_positions(pack):
    """render_display(hits=True) returns world positions: each lies on the far room's
    surfaces, the same pixels as at the origin shifted by the offset."""
    from gigascroll import runtime

    offset = DIRECTION * 3000
    g0 = Gallery.from_room(box_room(), pack)
    g = Gallery.from_room(shifted(box_room(), offset), pack)
    vt = runtime.VirtualTexture(pack, (16, 16))
    c0, c = g0.camera(SIZE), g.camera(SIZE)
    _, h0 = g0.render_display(c0, vt, lighting="unlit", hits=True)
    _, h = g.render_display(c, vt, lighting="unlit", hits=True)
    both = np.isfinite(h0["position"]).all(axis=2) & np.isfinite(h["position"]).all(axis=2)
    assert both.mean() > 0.99
    np.testing.assert_allclose(h["position"][both] - offset, h0["position"][both], atol=2e-3)
    assert (h["slot"] == h0["slot"]).mean() > 0.99


def test_camera_is_in_world_coordinates(pack):
    """A camera given in the world's coordinates sees the far room; the same camera without
    the offset sees nothing of it (the room is not silently moved back to the origin)."""
    offset = DIRECTION * 9000
    g = Gallery.from_room(shifted(box_room(), offset), pack)
    from gigascroll import runtime

    vt = runtime.VirtualTexture(pack, (16, 16))
    inside = Camera([0 + offset[0], 1.5 + offset[1], 1.8], [offset[0], 1.2 + offset[1], -2],
                    [0, 1, 0], 60.0, resolution=(32, 24))
    outside = Camera([0, 1.5, 1.8], [0, 1.2, -2], [0, 1, 0], 60.0, resolution=(32, 24))
    assert np.isfinite(g.render_display(inside, vt, lighting="unlit")).all()
    assert g.render_display(inside, vt, lighting="unlit").mean() > 0.1
    assert g.render_display(outside, vt, lighting="unlit").max() == 0

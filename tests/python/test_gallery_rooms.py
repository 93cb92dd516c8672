"""The built-in rooms against independent computations: trimesh ray casts for closure, the
scenarios' ExhibitionScene placements, hand-computed emitted power, and Monte Carlo
illuminance against the Lambert-formula calibration."""

import math

import numpy as np
import pytest
import trimesh

from gigascroll.room import builtin as rooms
from gigascroll.room.spec import RoomSpec
from gigascroll.room.builtin import ROOM_NAMES, builtin_room
from gigascroll.views.exhibition import SCROLL, TABLE4_PAINTINGS, multi_exhibition, single_scroll

SHELL = ("floor", "ceiling", "walls")
PACK_LIKE = [(p.name, p.width, p.height) for p in TABLE4_PAINTINGS]  # texels only, like a pack


def room_mesh(spec: RoomSpec, names=None) -> trimesh.Trimesh:
    parts = [trimesh.Trimesh(s.vertices, s.triangles, process=False) for s in spec.surfaces
             if names is None or s.name in names]
    return trimesh.util.concatenate(parts)


def first_hits(mesh, origins, directions):
    """Brute-force Moller-Trumbore: distance to the nearest triangle along each ray (inf: none)."""
    t = mesh.triangles
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    p = np.cross(directions[:, None, :], e2[None])
    det = np.einsum("rtk,tk->rt", p, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = origins[:, None, :] - t[None, :, 0]
        u = np.einsum("rtk,rtk->rt", s, p) * inv
        q = np.cross(s, e1[None])
        v = np.einsum("rk,rtk->rt", directions, q) * inv
        dist = np.einsum("tk,rtk->rt", e2, q) * inv
        ok = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (dist > 1e-9)
    return np.where(ok, dist, np.inf).min(axis=1)


def interior_points(spec: RoomSpec, rng, n):
    v = room_mesh(spec, SHELL).vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    return rng.uniform(lo + 0.05, hi - 0.05, size=(n, 3))


@pytest.mark.parametrize("name,count", [("scroll", None), ("hall", 8), ("hall", 40)])
def test_room_is_closed(name, count):
    spec = builtin_room(name, TABLE4_PAINTINGS, count)
    shell = room_mesh(spec, SHELL)
    shell.merge_vertices()
    assert shell.is_watertight
    rng = np.random.default_rng(1)
    origins = interior_points(spec, rng, 400)
    d = rng.normal(size=(400, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.isfinite(first_hits(shell, origins, d)).all()
    # Normals of the shell face into the room: the centre is on the front of every triangle.
    c = (shell.bounds[0] + shell.bounds[1]) / 2
    tri = shell.triangles
    assert (np.einsum("ij,ij->i", shell.face_normals, c - tri[:, 0]) > 0).all()


def test_every_surface_inside_the_shell_and_albedo_realistic():
    for name in ROOM_NAMES:
        spec = builtin_room(name, TABLE4_PAINTINGS)
        lo, hi = room_mesh(spec, SHELL).bounds
        for s in spec.surfaces:
            assert all(0 < a < 1 for a in s.albedo), s.name
            assert s.vertices.min(axis=0).round(9).tolist() >= lo.round(9).tolist() or \
                (s.vertices >= lo - 1e-9).all()
            assert (s.vertices >= lo - 1e-9).all() and (s.vertices <= hi + 1e-9).all(), s.name
            assert s.triangles.dtype == np.int64 and s.vertices.dtype == np.float64
        assert any(max(s.emission) > 0 for s in spec.surfaces)
        for slot in spec.paintings:
            corners = slot_corners(slot)
            assert (corners >= lo).all() and (corners <= hi).all()


def slot_corners(slot):
    o, u, v = (np.asarray(x) for x in (slot.origin, slot.u_axis, slot.v_axis))
    return np.array([o, o + u * slot.width_m, o + v * slot.height_m,
                     o + u * slot.width_m + v * slot.height_m])


def placement_of(p):
    return (np.array(p["origin"]), np.array(p["u_axis"]), np.array(p["v_axis"]),
            p["width_m"], p["height_m"])


def test_scroll_where_single_scroll_puts_it():
    spec = builtin_room("scroll", [SCROLL])
    ex = single_scroll()
    o, u, v, w, h = placement_of(ex.placements[0])
    (slot,) = spec.paintings
    assert slot.painting == 0
    np.testing.assert_array_equal(slot.origin, o)
    np.testing.assert_array_equal(slot.u_axis, u)
    np.testing.assert_array_equal(slot.v_axis, v)
    assert (slot.width_m, slot.height_m) == (w, h) == (12.0, 0.5)
    # by hand: top edge at 1.5 + 0.25, wall 5 mm behind, wall box of single_scroll
    assert slot.origin == (12.0, 1.75, 0.0)
    # From the room the scroll reads unmirrored: texel (0, 0) is on the left of the screen.
    from gigascroll import Camera
    cam = Camera((6.0, 1.5, -8.0), (6.0, 1.5, 0.0), (0.0, 1.0, 0.0), fov=90.0)
    first = cam.project(slot.origin)
    last = cam.project(tuple(np.add(slot.origin, np.multiply(slot.u_axis, slot.width_m))))
    assert first is not None and last is not None and first[0] < last[0]
    bounds = room_mesh(spec, SHELL).bounds
    np.testing.assert_allclose(bounds, [[-2.0, 0.0, -3.995], [14.0, 3.0, 0.005]])


def test_hall_where_multi_exhibition_puts_them():
    for count in (8, 24):
        spec = builtin_room("hall", TABLE4_PAINTINGS, count)
        ex = multi_exhibition(count)
        assert len(spec.paintings) == len(ex.placements) == count
        for i, (slot, p) in enumerate(zip(spec.paintings, ex.placements)):
            o, u, v, w, h = placement_of(p)
            assert slot.painting == p["painting"] % 8 == i % 8
            np.testing.assert_allclose(slot.origin, o, atol=1e-12)
            np.testing.assert_array_equal(slot.u_axis, u)
            np.testing.assert_array_equal(slot.v_axis, v)
            assert (slot.width_m, slot.height_m) == pytest.approx((w, h), rel=1e-12)
        # The paintings lie 1 mm above a table top, and inside it.
        tables = room_mesh(spec, ["tables"])
        corners = np.concatenate([slot_corners(s) for s in spec.paintings])
        inset = corners + 1e-6 * np.sign(corners.mean(axis=0) - corners) * [1, 0, 0]
        down = np.tile([0.0, -1.0, 0.0], (len(corners), 1))
        np.testing.assert_allclose(first_hits(tables, inset, down), 0.001, atol=1e-9)


def test_hall_tables_are_add_table_boxes():
    spec = builtin_room("hall", TABLE4_PAINTINGS, 16)
    tables = room_mesh(spec, ["tables"])
    # 2 tables of 5 boxes (12 triangles each); each box closed
    assert len(tables.faces) == 2 * 5 * 12
    tables.merge_vertices()
    assert tables.is_watertight and tables.euler_number == 2 * 10  # ten closed boxes
    # by hand: Table 4 sizes -> table length = widest painting + 2 gaps
    length = 196301 * 12 / 152089 + 0.2
    assert tables.bounds[1][0] - tables.bounds[0][0] == pytest.approx(length)
    assert tables.bounds[1][1] == pytest.approx(0.70)


def test_slots_take_the_pack_aspect():
    for name in ROOM_NAMES:
        spec = builtin_room(name, PACK_LIKE)
        for slot in spec.paintings:
            _, w, h = PACK_LIKE[slot.painting]
            assert slot.width_m / slot.height_m == pytest.approx(w / h, rel=1e-12)
    # a texel-only scroll is the seed's 12 m long
    (slot,) = builtin_room("scroll", PACK_LIKE).paintings
    assert slot.width_m == 12.0 and slot.height_m == pytest.approx(12 * 6083 / 152089)
    # a square painting in the scroll room is shrunk to fit the wall
    (slot,) = builtin_room("scroll", {"square": 1.0}).paintings
    assert slot.width_m == slot.height_m == rooms.SCROLL_MAX_HEIGHT


def area(s):
    t = s.vertices[s.triangles]
    return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()


def test_emitted_power_by_hand():
    spec = builtin_room("scroll", [SCROLL])
    spots = next(s for s in spec.surfaces if s.name == "spot_lights")
    fill = next(s for s in spec.surfaces if s.name == "fill_light")
    # 8 spots of 0.3 m x 0.3 m; the fill 14 m x 1.5 m
    assert area(spots) == pytest.approx(8 * 0.09)
    assert area(fill) == pytest.approx((16 - 2) * (4 - 1 - 1.5))
    by_hand = math.pi * (8 * 0.09 * spots.emission[0] + 14 * 1.5 * fill.emission[0])
    np.testing.assert_allclose(rooms.emitted_power(spec), [by_hand] * 3, rtol=1e-12)
    hall = builtin_room("hall", TABLE4_PAINTINGS, 40)
    lights = next(s for s in hall.surfaces if s.name == "ceiling_lights")
    # 5 tables x 8 x 2 panels of 0.6 m x 0.6 m
    assert len(lights.triangles) == 2 * 5 * 8 * 2
    np.testing.assert_allclose(rooms.emitted_power(hall),
                               [math.pi * 80 * 0.36 * lights.emission[0]] * 3, rtol=1e-12)


def mc_irradiance(spec, point, normal, rng, n=400_000):
    """Monte Carlo: E = sum over emitters of L cos cos' / r^2 dA, uniform area samples."""
    e = 0.0
    for s in spec.surfaces:
        if max(s.emission) <= 0:
            continue
        t = s.vertices[s.triangles]
        cross = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        areas = 0.5 * np.linalg.norm(cross, axis=1)
        k = rng.choice(len(t), size=n, p=areas / areas.sum())
        a, b = rng.random(n), rng.random(n)
        flip = a + b > 1
        a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
        x = t[k, 0] + a[:, None] * (t[k, 1] - t[k, 0]) + b[:, None] * (t[k, 2] - t[k, 0])
        nl = cross[k] / (2 * areas[k, None])
        d = x - np.asarray(point)
        r2 = (d * d).sum(axis=1)
        cos_r = np.clip(d @ np.asarray(normal), 0, None) / np.sqrt(r2)
        cos_l = np.clip(-(d * nl).sum(axis=1), 0, None) / np.sqrt(r2)
        e += s.emission[0] * areas.sum() * np.mean(cos_r * cos_l / r2)
    return e


def test_illuminance_is_gallery_like():
    rng = np.random.default_rng(7)
    spec = builtin_room("scroll", [SCROLL])
    (slot,) = spec.paintings
    face = [0.0, 0.0, -1.0]
    centre = (6.0, 1.5, 0.0)
    lux = mc_irradiance(spec, centre, face, rng) * rooms.LUMENS_PER_WATT
    assert lux == pytest.approx(rooms.direct_irradiance(spec, centre, face)[0] * 683, rel=0.02)
    # along the scroll 150..300 lux eq. of direct light
    for x in np.linspace(0.5, 11.5, 5):
        lx = rooms.direct_irradiance(spec, (x, 1.5, 0.0), face)[0] * 683
        assert 150 <= lx <= 300, (x, lx)
    hall = builtin_room("hall", TABLE4_PAINTINGS, 8)
    up = [0.0, 1.0, 0.0]
    centres = [np.asarray(s.origin) + 0.5 * (np.asarray(s.u_axis) * s.width_m
                                             + np.asarray(s.v_axis) * s.height_m)
               for s in hall.paintings]
    lux = [mc_irradiance(hall, c, up, rng, 100_000) * 683 for c in centres]
    assert np.mean(lux) == pytest.approx(rooms.GALLERY_LUX, rel=0.03)
    assert 100 < min(lux) and max(lux) < 300


def test_spots_aimed_at_thirty_degrees():
    spec = builtin_room("scroll", [SCROLL])
    spots = next(s for s in spec.surfaces if s.name == "spot_lights")
    t = spots.vertices[spots.triangles]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    off_vertical = np.degrees(np.arccos(-n[:, 1]))
    np.testing.assert_allclose(off_vertical, 30.0, atol=1e-9)
    # each aims at the centre line: the normal ray from the panel centre meets z = 0 at 1.5 m
    c = np.repeat(spots.vertices.reshape(-1, 4, 3).mean(axis=1), 2, axis=0)  # quad centres
    s = -c[:, 2] / n[:, 2]
    np.testing.assert_allclose(c[:, 1] + s * n[:, 1], 1.5, atol=1e-9)


def test_bad_arguments():
    with pytest.raises(ValueError, match="unknown room"):
        builtin_room("attic", TABLE4_PAINTINGS)
    for count in (0, 7, 48, -8, 8.0):
        with pytest.raises(ValueError, match="count"):
            builtin_room("hall", TABLE4_PAINTINGS, count)
    with pytest.raises(ValueError):
        builtin_room("scroll", TABLE4_PAINTINGS, 2)
    for bad in ([], [("a", 0, 1)], {"a": float("nan")}, 3, [("a", 1e9, 1)]):
        with pytest.raises(ValueError):
            builtin_room("hall", bad)


def photon_scene(spec):
    """The room in the photon renderer's Scene, paintings as grey quads (albedo 0.5)."""
    from gigascroll import Scene

    scene = Scene()
    for s in spec.surfaces:
        scene.add_mesh(s.vertices, s.triangles, albedo=s.albedo, emission=s.emission)
    for slot in spec.paintings:
        c = slot_corners(slot)[[0, 1, 3, 2]]
        scene.add_mesh(c, np.array([[0, 1, 2], [0, 2, 3]]), albedo=(0.5, 0.5, 0.5))
    scene.commit()
    return scene


@pytest.mark.parametrize("name", ROOM_NAMES)
def test_direct_light_matches_the_photon_renderer(name):
    """The Lambert-formula calibration against the photon renderer's light sampling (Embree,
    shadow rays): a narrow camera on a painting's centre sees 0.5 * E_direct / pi."""
    from gigascroll import Camera, render

    spec = builtin_room(name, TABLE4_PAINTINGS)
    scene = photon_scene(spec)
    slot = spec.paintings[0]
    o, u, v = (np.asarray(x) for x in (slot.origin, slot.u_axis, slot.v_axis))
    centre = o + (u * slot.width_m + v * slot.height_m) / 2
    front = np.cross(v, u)  # the side the room is on: both rooms read unmirrored from it
    cam = Camera(tuple(centre + 0.5 * front), tuple(centre), tuple(-v), fov=1.0,
                 resolution=(8, 8))
    img = render(scene, cam, photons=1000, radius=0.05, spp=4, light_samples=64,
                 indirect=False)
    expected = 0.5 * rooms.direct_irradiance(spec, centre, front) / math.pi
    np.testing.assert_allclose(img.mean(axis=(0, 1)), expected, rtol=0.02)


def test_lambert_formula_against_the_rectangle_form_factor():
    """Point under the corner of an a x b rectangle at distance c, planes parallel:
    F = 1/(2 pi) [A/sqrt(1+A^2) atan(B/sqrt(1+A^2)) + B/sqrt(1+B^2) atan(A/sqrt(1+B^2))],
    A = a/c, B = b/c; E = pi F for unit radiance (Howell's catalogue, configuration B-3)."""
    for a, b, c in ((1.0, 1.0, 1.0), (0.3, 2.0, 0.7), (5.0, 0.1, 3.0)):
        A, B = a / c, b / c
        f = (A / math.sqrt(1 + A * A) * math.atan(B / math.sqrt(1 + A * A))
             + B / math.sqrt(1 + B * B) * math.atan(A / math.sqrt(1 + B * B))) / (2 * math.pi)
        quad = [[0, c, 0], [a, c, 0], [a, c, b], [0, c, b]]  # counter-clockwise from below
        assert rooms.polygon_irradiance([0, 0, 0], [0, 1, 0], quad) == pytest.approx(
            math.pi * f, rel=1e-12)
        assert rooms.polygon_irradiance([0, 0, 0], [0, 1, 0], quad[::-1]) == 0.0  # its back

"""Light in the gallery against analytic answers: a furnace-style closed room, the same room at
1e-3 and 1e3 scale, a painting 1 mm in front of its wall, a painting seen at grazing angles."""

import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll.gallery import Gallery, PaintingSlot, RoomSpec, Surface, painting_albedo
from gigascroll.photon import relmse

from gallery_checks import box_room, quad, uniform_pack


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("gallight") / "p.pack",
                        {"grey": (200, 200, 200), "wallish": (216, 216, 216), "red": (230, 30, 20)})


def albedo_of(pack, name):
    colour = {"grey": 200, "wallish": 216}[name]
    return float(painting_albedo(np.array([colour], np.uint8))[0])


def test_furnace_room_converges_to_the_analytic_radiance(pack):
    """Every wall emits Le = 1 and reflects rho = 0.5: the room's radiance is Le / (1 - rho) = 2
    everywhere, and a small painting of albedo rho_p (not emitting) shows rho_p x 2."""
    rho = 0.5
    surfaces = []
    for name, (c, a, b) in {"floor": ((0, 0, 0), (0, 0, 2), (2, 0, 0)), "ceiling": ((0, 3, 0), (2, 0, 0), (0, 0, 2)),
                            "back": ((0, 1.5, -2), (2, 0, 0), (0, 1.5, 0)), "front": ((0, 1.5, 2), (0, 1.5, 0), (2, 0, 0)),
                            "left": ((-2, 1.5, 0), (0, 1.5, 0), (0, 0, 2)), "right": ((2, 1.5, 0), (0, 0, 2), (0, 1.5, 0))}.items():
        v, t = quad(c, a, b)
        surfaces.append(Surface(name, v, t, (rho,) * 3, (1.0, 1.0, 1.0)))
    slot = PaintingSlot("grey", origin=(-0.2, 1.6, -1.999), u_axis=(1, 0, 0), v_axis=(0, -1, 0),
                        width_m=0.4, height_m=0.2)
    gal = Gallery.from_room(RoomSpec("furnace", surfaces, [slot]), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=400_000, light_samples=64)
    gal.bake(spacing=0.25, light_samples=64)
    cam = g.Camera([0, 1.5, 0.5], [0, 1.5, -2], [0, 1, 0], 40, resolution=(40, 40))
    rho_p = albedo_of(pack, "grey")
    for lighting in ("full", "baked"):
        rgb, hits = gal.render_display(cam, vt, lighting=lighting, hits=True)
        on = hits["slot"] == 0
        pos = hits["position"]
        wall = (hits["slot"] == -1) & (np.abs(pos[..., 1] - 1.5) < 0.5) & (np.abs(pos[..., 0]) < 0.8) \
            & (np.abs(pos[..., 1] - 1.5) > 0.2)
        assert on.sum() > 20 and wall.sum() > 100
        # The painting blocks 0.1% of the room's emitting area: a bias far below the bound.
        assert rgb[wall].mean() == pytest.approx(1 / (1 - rho), rel=0.03), lighting
        assert rgb[on].mean() == pytest.approx(rho_p / (1 - rho), rel=0.04), lighting


def render_box(pack, scale, lighting, size=(32, 24)):
    gal = Gallery.from_room(box_room(scale=scale, painting="red"), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=100_000)
    if lighting == "baked":
        gal.bake()
    return gal.render_display(gal.camera(size, fov=70), vt, lighting=lighting), gal.stats


@pytest.mark.parametrize("lighting", ["full", "baked"])
def test_room_at_milli_and_kilo_scale_gives_the_same_image(pack, lighting):
    ref, stats = render_box(pack, 1.0, lighting)
    for scale in (1e-3, 1e3):
        img, s = render_box(pack, scale, lighting)
        assert s["radius"] == pytest.approx(stats["radius"] * scale, rel=1e-3)
        assert np.isfinite(img).all()
        # Photon paths and light samples are the same up to float rounding, so the images
        # are nearly identical (a noise-free difference, far below the Mitsuba bounds).
        assert relmse(img, ref) < 2e-4, (scale, relmse(img, ref))


def test_painting_1mm_in_front_of_its_wall_neither_leaks_nor_shadows_itself(pack):
    """The painting's irradiance equals that of the bare wall it hangs on (same albedo, so
    the room's light is the same): no self-shadowing by the wall 1 mm behind, no light leaking
    from behind it."""
    rho = albedo_of(pack, "wallish")
    vt = g.VirtualTexture(pack)
    images = {}
    for with_painting in (True, False):
        spec = box_room(painting="wallish", wall=(rho,) * 3, gap=0.001)
        if not with_painting:
            spec.paintings = []
        gal = Gallery.from_room(spec, pack)
        gal.light(vt, photons=400_000, light_samples=64)
        gal.bake(spacing=0.1)
        cam = g.Camera([0, 1.5, 0.0], [0, 1.5, -2], [0, 1, 0], 40, resolution=(32, 32))
        images[with_painting] = {m: gal.render_display(cam, vt, lighting=m, hits=True) for m in ("full", "baked")}
    on = images[True]["full"][1]["slot"] == 0
    assert on.sum() > 200
    for m in ("full", "baked"):
        painted, bare = images[True][m][0][on], images[False][m][0][on]
        assert painted.mean() == pytest.approx(bare.mean(), rel=0.02), m
        assert relmse(painted, bare) < 2e-3, m


def test_painting_at_grazing_angles_stays_finite_and_coloured(pack):
    spec = box_room(painting="red")
    gal = Gallery.from_room(spec, pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=50_000)
    gal.bake(spacing=0.2)
    expected = painting_albedo(np.array([230, 30, 20], np.uint8))
    # Eyes 1, 5 and 20 cm in front of the back wall, looking along it.
    for dz in (0.01, 0.05, 0.2):
        cam = g.Camera([1.9, 1.5, -2 + dz], [-1.9, 1.5, -2 + dz], [0, 1, 0], 60, resolution=(64, 48))
        for m in ("unlit", "full", "baked"):
            rgb, hits = gal.render_display(cam, vt, lighting=m, hits=True)
            assert np.isfinite(rgb).all() and (rgb >= 0).all()
            on = hits["slot"] == 0
            if m == "unlit" and dz >= 0.05:
                assert on.sum() > 0
                assert np.isfinite(hits["lod"][on]).all() and hits["lod"][on].max() > 2
                assert np.allclose(rgb[on], expected, rtol=0.02)


def _rotation(yaw_deg, pitch_deg):
    a, b = math.radians(yaw_deg), math.radians(pitch_deg)
    ry = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    rx = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    return ry @ rx


def test_grazing_light_on_an_oblique_painting_matches_quadrature(pack):
    """A painting on an oblique plane lit by a panel almost in its plane (incidence ~84-88
    degrees): full and baked lighting against a midpoint quadrature of the panel's irradiance.
    Black walls, so only the direct light counts."""
    R = _rotation(37, 12)
    u, v = R @ np.array([1.0, 0, 0]), R @ np.array([0, -1.0, 0])
    n = np.cross(v, u)  # the painting's viewed side (u x v points away from the viewer)
    origin = np.array([0.0, 1.5, 0.0]) - 0.5 * u - 0.25 * v
    # The panel: 0.4 m square, 2 m along the plane and 0.1 m off it, facing back at the painting.
    centre = np.array([0.0, 1.5, 0.0]) + 2.0 * u + 0.1 * n
    pa, pb = 0.2 * v, 0.2 * n  # half-edges; panel normal = -u side
    if np.dot(np.cross(pa, pb), -u) < 0:
        pa = -pa
    verts = np.array([centre - pa - pb, centre + pa - pb, centre + pa + pb, centre - pa + pb])
    surfaces = [Surface("light", verts, np.array([[0, 1, 2], [0, 2, 3]]), (0.0, 0.0, 0.0), (2000.0, 2000.0, 2000.0))]
    for name, (c, a, b) in {"floor": ((0, 0, 0), (0, 0, 4), (4, 0, 0)), "ceiling": ((0, 4, 0), (4, 0, 0), (0, 0, 4))}.items():
        qv, qt = quad(c, a, b)
        surfaces.append(Surface(name, qv, qt, (0.0, 0.0, 0.0)))
    slot = PaintingSlot("grey", origin=tuple(origin), u_axis=tuple(u), v_axis=tuple(v), width_m=1.0, height_m=0.5)
    gal = Gallery.from_room(RoomSpec("grazing", surfaces, [slot]), pack)
    vt = g.VirtualTexture(pack)
    gal.light(vt, photons=20_000, light_samples=4096)
    gal.bake(spacing=0.1, light_samples=4096)
    eye = np.array([0.0, 1.5, 0.0]) + 1.5 * n
    cam = g.Camera(list(eye), [0, 1.5, 0], [0, 1, 0], 30, resolution=(16, 16))
    rho = albedo_of(pack, "grey")
    m = 120
    s = (np.arange(m) + 0.5) / m * 2 - 1
    A, B = np.meshgrid(s, s)
    pts = centre + A[..., None] * pa + B[..., None] * pb
    ln = np.cross(pa, pb) / np.linalg.norm(np.cross(pa, pb))
    dA = 4 * np.linalg.norm(pa) * np.linalg.norm(pb) / m ** 2
    for lighting in ("full", "baked"):
        rgb, hits = gal.render_display(cam, vt, lighting=lighting, hits=True)
        on = np.argwhere(hits["slot"] == 0)
        assert len(on) > 40
        for y, x in on[:: len(on) // 12]:
            p = hits["position"][y, x].astype(float)
            L = pts - p
            d2 = (L ** 2).sum(-1)
            cos_x = np.clip(L @ n, 0, None) / np.sqrt(d2)
            cos_l = np.clip(-(L @ ln), 0, None) / np.sqrt(d2)
            E = 2000.0 * (cos_x * cos_l / d2).sum() * dA
            assert rho * E / math.pi > 0.02  # a lit point, not a trivially dark one
            assert rgb[y, x, 0] == pytest.approx(rho * E / math.pi, rel=0.04), (lighting, y, x)

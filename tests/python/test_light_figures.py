"""The light's figures as conservators use them (gigascroll light, room/lights.py,
gallery/illuminance.py) against analytic answers.

A room made here: a black box (albedo 0 everywhere, the light panel's diffuser too), so only
direct light reaches the painting, and one rectangular light above a painting that lies on
the floor facing up. References: the rectangle's closed-form form factor (Howell's catalogue,
configuration B-3, for a point under a corner of a parallel rectangle) and Lambert's polygon
formula; the built-in rooms' emission as the code before light specs computed it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import gigascroll as g
from gigascroll import cli
from gigascroll.gallery import Gallery, PaintingSlot
from gigascroll.gallery.conservation import LIMITS, check_exposure
from gigascroll.gallery.illuminance import lux_stats, painting_lux
from gigascroll.room.lights import LightSpec, light_surface, rectangle
from gigascroll.room.polygon import unit_irradiance
from gigascroll.room.files import save_room
from gigascroll.room.builtin import builtin_room
from gigascroll.room.slot_grid import slot_front, slot_points

from gallery_checks import box_room, uniform_pack

BLACK = (0.0, 0.0, 0.0)
HEIGHT = 2.999       # box_room's ceiling light plane
PANEL = (1.2, 0.8)   # the test light: 1.2 m along x, 0.8 m along z, centred over the painting


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("lightfig") / "p.pack", {"grey": (200, 200, 200)})


def black_room(light: LightSpec | None = None):
    """box_room with black walls, its painting moved onto the floor (facing up, 1 mm above
    it), and its light replaced by `light` (None: the box's own, dark-diffused)."""
    room = box_room(floor=BLACK, wall=BLACK, painting="grey")
    room.paintings = [PaintingSlot("grey", origin=(-1.0, 0.001, -0.5), u_axis=(1, 0, 0),
                                   v_axis=(0, 0, 1), width_m=2.0, height_m=1.0, name="main")]
    if light is not None:
        room.surfaces = [s for s in room.surfaces if s.name != "light"]
        room.surfaces.append(light_surface(light, room.paintings))
        room.lights = [light]
    return room


def panel_light(**target) -> LightSpec:
    return LightSpec("panel", [rectangle((0.0, HEIGHT, 0.0), (0, -1, 0), *PANEL)],
                     kelvin=4000, albedo=BLACK, **target)


def corner_irradiance(a: float, b: float, c: float) -> float:
    """Irradiance from a unit-radiance a x b rectangle, parallel to the receiver at height c,
    at the point under one of its corners: pi x the form factor (Howell B-3)."""
    A, B = a / c, b / c
    return (A / math.sqrt(1 + A * A) * math.atan(B / math.sqrt(1 + A * A))
            + B / math.sqrt(1 + B * B) * math.atan(A / math.sqrt(1 + B * B))) / 2


def rectangle_irradiance(x: float, z: float, c: float) -> float:
    """E at floor point (x, z) under the PANEL centred at the origin, by superposing the four
    corner rectangles (signed where the point lies outside a side)."""
    total = 0.0
    for s1, a in ((1, PANEL[0] / 2 - x), (1, PANEL[0] / 2 + x)):
        for s2, b in ((1, PANEL[1] / 2 - z), (1, PANEL[1] / 2 + z)):
            sign = math.copysign(1, a) * math.copysign(1, b)
            total += sign * corner_irradiance(abs(a), abs(b), c)
    return total


def test_the_corner_superposition_is_lamberts_formula():
    # The two analytic references agree (the superposition is only used inside the panel's
    # footprint below, but holds outside too).
    quad = rectangle((0.0, HEIGHT, 0.0), (0, -1, 0), *PANEL)
    for x, z in ((0.0, 0.0), (0.3, -0.2), (0.55, 0.35), (0.9, 0.1)):
        want = unit_irradiance([(x, 0.001, z)], (0, 1, 0), [quad])[0, 0]
        assert rectangle_irradiance(x, z, HEIGHT - 0.001) == pytest.approx(want, rel=1e-9)


def test_gallery_illuminance_under_a_rectangular_light_is_the_polygon_formula(pack):
    """The core's baked irradiance (at a fine lattice) on the painting under the light, in
    lux, within 1 % of the analytic direct illuminance at every grid point (asserted to
    0.1 %: the bake's analytic direct light is exact where nothing shadows, 2e-5 measured)."""
    light = panel_light(lumens=2000.0)
    room = black_room(light)
    gallery = Gallery.from_room(room, pack)
    vt = g.VirtualTexture(pack, (8, 8))
    gallery.light(vt, photons=20000, threads=2)
    gallery.bake(spacing=0.02, threads=2)
    lux, positions = painting_lux(gallery, vt, 0, samples=32)
    points = slot_points(room.paintings[0], 32)
    np.testing.assert_allclose(positions, points, atol=1e-4)  # the camera's pixels are the grid
    radiance = light.details["radiance"]
    assert light.details["lumens"] == pytest.approx(2000.0, rel=1e-12)
    # Y of the colour is 1, so lux = 683 x radiance x unit irradiance.
    want = np.array([[683 * radiance * rectangle_irradiance(p[0], p[2], HEIGHT - 0.001)
                      for p in row] for row in points])
    np.testing.assert_allclose(lux, want, rtol=1e-3)
    # and lighting "full" (emitter samples at each point) agrees on the mean
    full, _ = painting_lux(gallery, vt, 0, samples=32, lighting="full")
    assert np.nanmean(full) == pytest.approx(want.mean(), rel=0.01)


def test_lumens_are_the_panels_luminous_flux():
    """flux = 683 x pi x area x radiance for a Lambertian panel at unit luminance."""
    light = panel_light(lumens=1234.0)
    surface = light_surface(light, [])
    area = PANEL[0] * PANEL[1]
    emission = np.array(surface.emission)
    luminance = emission @ [0.2126, 0.7152, 0.0722]
    assert 683 * math.pi * area * luminance == pytest.approx(1234.0, rel=1e-9)


def test_a_light_solved_for_50_lux_gives_50_lux(pack, tmp_path):
    """A light spec with lux 50 on painting 'main', given to `gigascroll light` in a lights
    file for a room file: the command's own figures (baked, as the renders) and the analytic
    direct illuminance on its grid both give a mean of 50 lx within 1 %."""
    room_file = tmp_path / "black.glb"
    save_room(black_room(), room_file)
    spec = {"name": "solved", "centre": [0.2, HEIGHT, 0.1], "aim": [0, -1, 0],
            "width": PANEL[0], "height": PANEL[1], "kelvin": 3000, "lux": 50,
            "painting": "main"}
    (tmp_path / "lights.json").write_text(json.dumps([spec]))
    out = tmp_path / "report"
    code = cli.main(["light", str(pack.path), "--room", str(room_file), "--lights",
                     str(tmp_path / "lights.json"), "--photons", "20000", "--threads", "2",
                     "--samples", "64", "-o", str(out)])
    assert code == 0
    results = json.loads((out / "light.json").read_text())
    (figures,) = results["paintings"]
    assert figures["mean_lux"] == pytest.approx(50.0, rel=0.01)
    assert figures["direct_mean_lux_analytic"] == pytest.approx(50.0, rel=0.01)
    # Independently of the command: the solved radiance through Lambert's formula.
    (light,) = results["lights"]
    quad = rectangle(spec["centre"], spec["aim"], spec["width"], spec["height"])
    slot = black_room().paintings[0]
    unit = unit_irradiance(slot_points(slot, 64).reshape(-1, 3), slot_front(slot), [quad])
    assert 683 * light["radiance"] * unit.mean() == pytest.approx(50.0, rel=0.01)
    # The peak is above 50 lx: the high category's limit is exceeded there, and said.
    assert figures["max_lux"] > 50 and any("50 lx limit" in w for w in figures["warnings"])
    # 8 h x 300 days by default; the high category's 15 000 lx h a year at the brightest point
    assert figures["annual_lux_hours_mean"] == pytest.approx(2400 * figures["mean_lux"])
    assert figures["max_hours_per_year"] == pytest.approx(15_000 / figures["max_lux"])
    assert (out / figures["map"]).stat().st_size > 1000
    assert "<img src='map000.png'" in (out / "index.html").read_text()


def test_the_yearly_dose_and_the_warnings():
    lux = np.array([[40.0, 50.0], [60.0, np.nan]])
    s = lux_stats(lux)
    assert (s["min_lux"], s["mean_lux"], s["max_lux"]) == (40.0, 50.0, 60.0)
    assert s["uniformity"] == pytest.approx(0.8) and s["seen_share"] == 0.75
    # 50 lx, 8 h a day, 300 days: 120 000 lx h, within medium (150 000), over high (15 000)
    assert check_exposure(LIMITS["medium"], 50.0, 120_000.0) == []
    high = check_exposure(LIMITS["high"], 50.0, 120_000.0)
    assert len(high) == 1 and "15,000 lx h" in high[0]
    assert len(check_exposure(LIMITS["low"], 201.0, 600_001.0)) == 2
    assert check_exposure(LIMITS["none"], 1e6, 1e12) == []


# Emission of the built-in rooms' lights as the code before light specs computed it (same
# formulas, written out per room): white, equal channels.
BEFORE = {
    ("scroll", "a"): {"spot_lights": 9.724666292097448, "fill_light": 0.07301924867737127},
    ("hall", "a"): {"ceiling_lights": 8.843166476164427},
    ("scroll", "b"): {"spot_lights": 14.784624142998993, "fill_light": 0.09912742434781296},
    ("hall", "b"): {"ceiling_lights": 8.921845410460646},
}
PAINTINGS = {"a": [(30000, 1200)], "b": {"x": (1000, 800), "y": (640, 2000), "z": (5000, 1000)}}


@pytest.mark.parametrize("room, paintings", sorted(BEFORE))
def test_builtin_rooms_keep_their_light(room, paintings):
    spec = builtin_room(room, PAINTINGS[paintings])
    emitting = {s.name: s.emission for s in spec.surfaces if max(s.emission) > 0}
    assert set(emitting) == set(BEFORE[room, paintings])
    for name, value in BEFORE[room, paintings].items():
        np.testing.assert_allclose(emitting[name], (value,) * 3, rtol=1e-12)
    assert [light.name for light in spec.lights] == list(BEFORE[room, paintings])


def test_builtin_rooms_take_light_specs():
    light = LightSpec("track", [rectangle((6.0, 2.9, -1.0), (0, -1, 1), 0.3, 0.3)],
                      kelvin=2700, lux=50, painting=0)
    spec = builtin_room("scroll", PAINTINGS["a"], lights=[light])
    (emitter,) = [s for s in spec.surfaces if max(s.emission) > 0]
    assert emitter.name == "track" and emitter.emission[0] > emitter.emission[2]  # warm
    slot = spec.paintings[0]
    unit = unit_irradiance(slot_points(slot, 64).reshape(-1, 3), slot_front(slot),
                           light.panels).sum(axis=1)
    y = np.array(emitter.emission) @ [0.2126, 0.7152, 0.0722]
    assert 683 * y * unit.mean() == pytest.approx(50.0, rel=1e-9)


@pytest.mark.parametrize("bad, match", [
    ({"lux": 50}, "exactly one of painting or points"),
    ({"lux": 50, "lumens": 10, "painting": "main"}, "exactly one of lumens or lux"),
    ({}, "exactly one of lumens or lux"),
    ({"lux": float("nan"), "painting": "main"}, "lux must be positive"),
    ({"lux": 50, "painting": "nowhere"}, "no painting slot 'nowhere'"),
    ({"lumens": -1.0}, "lumens must be positive"),
])
def test_bad_light_specs_are_value_errors(bad, match):
    with pytest.raises(ValueError, match=match):
        light_surface(panel_light(**bad), black_room().paintings)


def test_a_light_behind_the_painting_is_refused():
    light = LightSpec("under", [rectangle((0.0, -0.5, 0.0), (0, 1, 0), 0.5, 0.5)], lux=50,
                      painting="main")
    with pytest.raises(ValueError, match="crosses the plane|faces the points"):
        light_surface(light, black_room().paintings)


def shifted_lux(pack, offset):
    """The lux grid of the black room with its light, every coordinate moved by `offset`."""
    light = LightSpec("panel", [rectangle(np.array((0.0, HEIGHT, 0.0)) + offset, (0, -1, 0),
                                          *PANEL)], kelvin=4000, albedo=BLACK, lumens=2000.0)
    room = black_room()
    room.surfaces = [s for s in room.surfaces if s.name != "light"]
    for s in room.surfaces:
        s.vertices = s.vertices + offset
    s0 = room.paintings[0]
    room.paintings = [PaintingSlot(s0.painting, tuple(np.add(s0.origin, offset)), s0.u_axis,
                                   s0.v_axis, s0.width_m, s0.height_m, name=s0.name)]
    room.surfaces.append(light_surface(light, room.paintings))
    gallery = Gallery.from_room(room, pack)
    vt = g.VirtualTexture(pack, (8, 8))
    gallery.light(vt, photons=5000, threads=2)
    gallery.bake(spacing=0.05, threads=2)
    lux, positions = painting_lux(gallery, vt, 0, samples=16)
    return lux, positions, np.array(gallery.origin)


def test_a_room_far_from_the_origin_measures_the_same(pack):
    """The gallery holds a room 8.6 km out around itself (Gallery.origin); the measuring
    camera and the returned positions are in world coordinates."""
    offset = np.array([5000.0, 0.0, -7000.0])
    near, p_near, o_near = shifted_lux(pack, np.zeros(3))
    far, p_far, o_far = shifted_lux(pack, offset)
    assert not o_near.any() and o_far.any()  # the second room is held around itself
    np.testing.assert_allclose(p_far - offset, p_near, atol=1e-3)
    np.testing.assert_allclose(far, near, rtol=1e-3)

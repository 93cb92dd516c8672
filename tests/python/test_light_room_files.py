"""Light specs in room files: a glTF node whose extras hold {"light": {...}} becomes a
LightSpec, its emission solved for the lux it should give a painting (checked with Lambert's
formula, room/polygon.py) or for its lumens (flux = 683 x pi x area x luminance)."""

import math

import numpy as np
import pytest

from gigascroll.room.polygon import unit_irradiance
from gigascroll.room.files import load_room, save_room, write_gltf
from gigascroll.room.slot_grid import slot_front, slot_points

from test_light_figures import black_room

SIZES = {"grey": (2000, 1000)}
# counter-clockwise seen from below: it emits downward
PANEL = np.array([[-0.3, 2.9, -0.2], [0.3, 2.9, -0.2], [0.3, 2.9, 0.2], [-0.3, 2.9, 0.2]])


def room_with_light_node(tmp_path, light, name="room.glb", panel=PANEL):
    """black_room as a glTF file, plus a light node (a 0.6 m x 0.4 m panel facing down)."""
    base = tmp_path / f"base-{name}"
    save_room(black_room(), base)
    room = load_room(base, SIZES)
    nodes = [dict(name=s.name, vertices=s.vertices, triangles=s.triangles, albedo=s.albedo,
                  emission=s.emission) for s in room.surfaces]
    slot = room.paintings[0]
    o, u, v = (np.array(x) for x in (slot.origin, slot.u_axis, slot.v_axis))
    corners = np.array([o, o + slot.height_m * v, o + slot.width_m * u + slot.height_m * v,
                        o + slot.width_m * u])  # facing v x u, the painting's front
    nodes.append(dict(name=slot.name, vertices=corners, triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                      extras={"painting": "grey", "up": [-x for x in slot.v_axis]}))
    nodes.append(dict(name="track", vertices=panel, triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                      albedo=(0.5, 0.5, 0.5), extras={"light": light}))
    return write_gltf(nodes, tmp_path / name)


def test_a_light_node_solved_for_lux_on_a_painting(tmp_path):
    path = room_with_light_node(tmp_path, {"kelvin": 2700, "lux": 80, "painting": "grey"})
    room = load_room(path, SIZES)
    (light,) = room.lights
    (surface,) = [s for s in room.surfaces if s.name == "track"]
    assert surface.albedo == (0.5, 0.5, 0.5)
    slot = room.paintings[0]
    unit = unit_irradiance(slot_points(slot, 64).reshape(-1, 3), slot_front(slot), [PANEL])
    y = np.array(surface.emission) @ [0.2126, 0.7152, 0.0722]
    assert 683 * y * unit.mean() == pytest.approx(80.0, rel=1e-5)  # float32 positions in glTF
    assert surface.emission[0] > surface.emission[1] > surface.emission[2]  # 2700 K is warm


def test_a_light_node_given_in_lumens(tmp_path):
    room = load_room(room_with_light_node(tmp_path, {"lumens": 900}), SIZES)
    (surface,) = [s for s in room.surfaces if s.name == "track"]
    assert surface.emission[0] == surface.emission[1] == surface.emission[2]  # white
    assert 683 * math.pi * 0.24 * surface.emission[0] == pytest.approx(900, rel=1e-5)


@pytest.mark.parametrize("light, match", [
    ({"lux": 80, "painting": "absent"}, "no painting slot 'absent'"),
    ({"lux": 80}, "exactly one of painting or points"),
    ({"lumens": 90, "watts": 3}, "unknown keys"),
    ({"lumens": 90, "kelvin": 1e9}, "colour temperature"),
    ({"lux": float("nan"), "painting": "grey"}, "lux must be positive"),
    ("bright", "must be an object"),
])
def test_bad_light_nodes_name_the_file(tmp_path, light, match):
    path = room_with_light_node(tmp_path, light)
    with pytest.raises(ValueError, match=match) as e:
        load_room(path, SIZES)
    assert str(path) in str(e.value)


def test_a_light_facing_away_from_its_painting_is_refused(tmp_path):
    path = room_with_light_node(tmp_path, {"lux": 80, "painting": "grey"}, panel=PANEL[::-1])
    with pytest.raises(ValueError, match="no panel faces the points"):
        load_room(path, SIZES)

"""The room of an exhibition as a `RoomSpec`: a built-in room, a room file, or a floor plan of
walls that gigascroll builds here.

A floor plan is a simple polygon of wall corners [x, z] (metres) and a wall height. Wall i runs
from corner i to corner i + 1; its inner side faces the room. A painting on wall i has its
centre `along_m` metres from the wall's first corner at `centre_height_m`, 5 mm in front of
the wall (in front of its frame's box when framed), image x running to the visitor's right.
Its slot is exactly width_cm / 100 x height_cm / 100 metres. Every painting (with its frame)
and every label must lie on its wall and overlap no other one: an ExhibitionError names the
painting, its size and the wall's, never a silent resize. Tables and vitrines are boxes under
their (possibly tilted) painting and must stand inside the floor plan without overlapping.

The floor and ceiling are the plan's bounding rectangle (the walls close the room); default
lights, when the file gives none, are one light per painting: a row of 0.3 m panels facing
down, 10 cm below the ceiling, one per 1.2 m of its width, each set back from the wall so
that the middle of its share of the painting lies 30 degrees off vertical from it (over a
table: straight above), solved together for the file's `lux` (default 200 lux) of direct
light on the painting."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..room.lights import LightSpec, light_surface, lights_from_json, rectangle
from ..room.spec import PaintingSlot, RoomSpec
from ..room.builtin import (CEILING_ALBEDO, FLOOR_ALBEDO, TABLE_ALBEDO,
                             WALL_ALBEDO, _box_quads, _quad, _surface)
from .labels import LABEL_GAP_M, LABEL_H_M, LABEL_W_M
from .model import Exhibition
from .schema import ExhibitionError

__all__ = ["build_room", "floor_polygon", "wall_frames", "WALL_GAP_M", "Wall"]

WALL_GAP_M = 0.005      # a painting's plane in front of its wall (or its frame's front)
SPOT_SIZE_M = 0.30
PANEL_SPAN_M = 1.2      # a default light's panels at most this far apart along its painting
DOWN = (0.0, -1.0, 0.0)  # the default lights' panels face down
SPOT_AIM_DEG = 30.0
TABLE_MARGIN_M = 0.05   # a table's top beyond its painting on each side


@dataclass
class Wall:
    """Wall i: its first corner a and last corner b ([x, z]), length, unit direction t and
    inward normal n (3-vectors, y = 0)."""
    a: np.ndarray
    b: np.ndarray
    length: float
    t: np.ndarray
    n: np.ndarray


def floor_polygon(ex: Exhibition, where: str | None = None):
    """The floor plan as a shapely Polygon (ExhibitionError unless simple and non-degenerate)."""
    from shapely.geometry import Polygon
    where = where or ex.path
    corners = [tuple(map(float, c)) for c in ex.room["walls"]]
    poly = Polygon(corners)
    if not poly.is_valid or poly.area < 1.0:
        raise ExhibitionError(f"{where}: room.walls: expected a simple polygon (walls that do "
                              f"not cross) of at least 1 m^2, got area {poly.area:.3g} m^2"
                              + ("" if poly.is_valid else " with crossing walls"))
    for i, (a, b) in enumerate(zip(corners, corners[1:] + corners[:1])):
        if math.dist(a, b) < 0.1:
            raise ExhibitionError(f"{where}: room.walls: expected walls of at least 10 cm, wall "
                                  f"{i} is {math.dist(a, b):.3g} m")
    return poly


def wall_frames(ex: Exhibition) -> list[Wall]:
    """Each wall's corners, length, direction and inward normal."""
    c = np.array(ex.room["walls"], dtype=np.float64)
    x, z = c[:, 0], c[:, 1]
    area = 0.5 * float(np.sum(x * np.roll(z, -1) - np.roll(x, -1) * z))
    sign = 1.0 if area > 0 else -1.0
    walls = []
    for i in range(len(c)):
        a, b = c[i], c[(i + 1) % len(c)]
        d = b - a
        length = float(np.hypot(*d))
        t = np.array([d[0], 0.0, d[1]]) / length
        walls.append(Wall(a, b, length, t, sign * np.array([-t[2], 0.0, t[0]])))
    return walls


def pack_name(p) -> str:
    """The name of painting `p` in the show's pack: its own, or its name in the given pack."""
    return p.pack_name


def build_room(ex: Exhibition, pack=None) -> RoomSpec:
    """The exhibition's RoomSpec; its slots show the pack's paintings by name (Painting.name;
    labels: `label-NAME`). `pack` (a TilePack) is needed for a room file only."""
    lights = _lights(ex)
    if "builtin" in ex.room:
        from ..room.builtin import builtin_room
        from ..room.sizes import PaintingSize
        sizes = [PaintingSize(p.name, p.pixels[0], p.pixels[1], p.width_m, p.height_m)
                 for p in ex.paintings]
        try:
            spec = builtin_room(ex.room["builtin"], sizes, lights=lights)
        except ValueError as e:
            raise ExhibitionError(f"{ex.path}: room.builtin: {e}") from None
        for slot in spec.paintings:  # by name: a given pack's order may differ
            slot.painting = pack_name(ex.paintings[int(slot.painting)])
        _check_all_shown(ex, [s.painting for s in spec.paintings], "room.builtin",
                         f"the {ex.room['builtin']!r} room shows "
                         f"{len(spec.paintings)} painting(s); the hall or a floor plan shows "
                         "them all")
        return spec
    if "file" in ex.room:
        return _file_room(ex, pack, lights)
    return _floor_plan_room(ex, lights)


def _check_all_shown(ex: Exhibition, shown: list, key: str, why: str) -> None:
    """ExhibitionError naming the first painting of the file that no slot shows: a painting
    is never left out silently."""
    for p in ex.paintings:
        if pack_name(p) not in shown:
            raise ExhibitionError(f"{ex.path}: {key}: expected a place for every painting, "
                                  f"{p.key} ({p.title[:80]!r}) has none ({why})")


def _lights(ex: Exhibition):
    if not ex.lights:
        return None
    by_title = {p.title: p.name for p in ex.paintings}
    names = {p.name for p in ex.paintings}
    data = []
    for i, x in enumerate(ex.lights):
        which = x.get("painting")
        if isinstance(which, str) and which not in by_title and which not in names or \
                isinstance(which, int) and not 0 <= which < len(ex.paintings):
            titles = ", ".join(repr(p.title) for p in ex.paintings[:10])
            raise ExhibitionError(f"{ex.path}: lights[{i}].painting: expected a painting's "
                                  f"title ({titles}) or index (0..{len(ex.paintings) - 1}), "
                                  f"got {which!r}"[:400])
        data.append(dict(x, painting=by_title.get(which, which)) if "painting" in x else x)
        try:
            lights_from_json(data[-1:])
        except ValueError as e:
            raise ExhibitionError(f"{ex.path}: lights[{i}]: {e}") from None
    try:
        return lights_from_json(data)
    except ValueError as e:
        raise ExhibitionError(f"{ex.path}: lights: {e}") from None


def _file_room(ex: Exhibition, pack, lights) -> RoomSpec:
    from ..room.files import load_room
    try:
        spec = load_room(ex.room["file"], pack)
    except (OSError, ValueError) as e:
        raise ExhibitionError(f"{ex.path}: room.file: {e}") from None
    names = [q.name for q in pack.paintings] if pack is not None else []
    placed = []
    for slot in spec.paintings:  # the file's placeholder sizes must be the physical sizes
        shown = names[slot.painting] if isinstance(slot.painting, int) and \
            0 <= slot.painting < len(names) else slot.painting
        placed.append(shown)
        p = next((q for q in ex.paintings if pack_name(q) == shown), None)
        if p is not None and (abs(slot.width_m - p.width_m) > 1e-3
                              or abs(slot.height_m - p.height_m) > 1e-3):
            raise ExhibitionError(
                f"{ex.path}: {p.key}.width_cm / height_cm: expected the room file's slot "
                f"{slot.width_m:.4g} m x {slot.height_m:.4g} m, got {p.width_m:.4g} m x "
                f"{p.height_m:.4g} m (sizes are never changed silently)")
    if pack is not None:
        _check_all_shown(ex, placed, "room.file", "the room file's placeholders show "
                         + ", ".join(repr(str(q)) for q in placed[:8])
                         + "; a painting's name names its placeholder")
    if lights is not None:
        spec.surfaces = [s for s in spec.surfaces if max(s.emission) <= 0]
        spec.surfaces += [light_surface(light, spec.paintings) for light in lights]
        spec.lights = list(lights)
    return spec


@dataclass
class _Item:
    key: str
    what: str
    wall: int
    lo: float       # along the wall
    hi: float
    bottom: float
    top: float


def _floor_plan_room(ex: Exhibition, lights) -> RoomSpec:
    poly = floor_polygon(ex)
    walls = wall_frames(ex)
    height = float(ex.room["height_m"])
    # Slot k shows painting k; the labels' slots follow the paintings'.
    slots, labels, frames, tables, items, footprints = [], [], [], [], [], []
    for p in ex.paintings:
        h = p.hang
        if h.wall is not None:
            slot, outer = _wall_slot(p, walls[h.wall], frames)
            items.append(_wall_item(ex, p.key, f"painting {p.title!r}", h.wall, walls[h.wall],
                                    h.along_m, h.centre_height_m, *outer, height))
            slots.append(slot)
            if ex.labels:
                labels.append(_label_slot(ex, p, walls[h.wall], outer, items, height))
        else:
            slot, table = _table_slot(ex, p, poly, footprints)
            slots.append(slot)
            tables += table
    slots += labels
    _check_overlaps(ex, items, walls)
    bounds = np.array(poly.bounds)  # minx, minz, maxx, maxz
    lo, hi = np.array([bounds[0], 0.0, bounds[1]]), np.array([bounds[2], height, bounds[3]])
    c, half = (lo + hi) / 2, (hi - lo) / 2
    ex_, ey, ez = np.eye(3)
    surfaces = [_surface("floor", [_quad(c - ey * half[1], ex_ * half[0], ez * half[2], ey)],
                         tuple(ex.room.get("floor_albedo", FLOOR_ALBEDO))),
                _surface("ceiling", [_quad(c + ey * half[1], ex_ * half[0], ez * half[2], -ey)],
                         tuple(ex.room.get("ceiling_albedo", CEILING_ALBEDO))),
                _surface("walls", [_wall_quad(w, height) for w in walls],
                         tuple(ex.room.get("wall_albedo", WALL_ALBEDO)))]
    for k, (quads, albedo) in enumerate(frames):
        surfaces.append(_surface(f"frame{k}", quads, albedo))
    if tables:
        surfaces.append(_surface("tables", tables, TABLE_ALBEDO))
    if lights is None:
        lights = _default_lights(ex, walls, height)
    surfaces += [light_surface(light, slots) for light in lights]
    eye, target = _suggested_view(ex, slots, poly)
    return RoomSpec(f"{ex.title}"[:80], surfaces, slots, camera_eye=eye, camera_target=target,
                    lights=list(lights))


def _wall_quad(w: Wall, height: float) -> np.ndarray:
    mid = (w.a + w.b) / 2
    centre = np.array([mid[0], height / 2, mid[1]])
    return _quad(centre, w.t * w.length / 2, np.array([0.0, height / 2, 0.0]), w.n)


def _oriented_box(centre, axes, halves) -> list[np.ndarray]:
    """The six faces (facing out) of a box with orthonormal `axes` and half sizes `halves`."""
    quads = []
    for k in range(3):
        a, b = [axes[i] * halves[i] for i in range(3) if i != k]
        for s in (-1.0, 1.0):
            n = axes[k] * s
            quads.append(_quad(centre + n * halves[k], a, b, n))
    return quads


def _wall_slot(p, w: Wall, frames: list):
    """The painting's slot on wall `w` and its outer (width, height) with the frame."""
    h = p.hang
    u = np.array([w.n[2], 0.0, -w.n[0]])  # the visitor's right, looking at the wall (-n)
    base = np.array([w.a[0], 0.0, w.a[1]]) + w.t * h.along_m
    fw = p.frame.width_m if p.frame else 0.0
    offset = WALL_GAP_M + (p.frame.depth_m if p.frame else 0.0)
    centre = base + np.array([0.0, h.centre_height_m, 0.0])
    origin = centre + w.n * offset - u * (p.width_m / 2) + np.array([0.0, p.height_m / 2, 0.0])
    slot = PaintingSlot(pack_name(p), tuple(float(x) for x in origin), tuple(float(x) for x in u),
                        (0.0, -1.0, 0.0), p.width_m, p.height_m, name=p.name)
    if p.frame:
        halves = (p.width_m / 2 + fw, p.height_m / 2 + fw, (offset - 1e-3) / 2)
        box_c = centre + w.n * ((offset - 1e-3) / 2 + 5e-4)
        frames.append((_oriented_box(box_c, (u, np.array([0.0, 1.0, 0.0]), w.n), halves),
                       p.frame.albedo))
    return slot, (p.width_m + 2 * fw, p.height_m + 2 * fw)


def _wall_item(ex, key, what, i, w: Wall, along, centre_h, width, height, wall_h) -> _Item:
    item = _Item(key, what, i, along - width / 2, along + width / 2, centre_h - height / 2,
                 centre_h + height / 2)
    if item.lo < -1e-9 or item.hi > w.length + 1e-9 or item.bottom < -1e-9 \
            or item.top > wall_h + 1e-9:
        raise ExhibitionError(
            f"{ex.path}: {key}.hang: expected {what} ({width:.4g} m x {height:.4g} m) to fit "
            f"wall {i} ({w.length:.4g} m long x {wall_h:.4g} m high); it spans "
            f"{item.lo:.4g}..{item.hi:.4g} m along the wall and {item.bottom:.4g}.."
            f"{item.top:.4g} m above the floor")
    return item


def _label_slot(ex, p, w: Wall, outer, items: list, wall_h: float) -> PaintingSlot:
    """The label beside the painting: to the visitor's right when there is room, else left;
    its bottom level with the painting's (with frame)."""
    h = p.hang
    u = np.array([w.n[2], 0.0, -w.n[0]])
    right_along = float(np.dot(u, w.t))  # +1: the visitor's right runs along the wall
    bottom = h.centre_height_m - outer[1] / 2
    centre_h = max(bottom + LABEL_H_M / 2, LABEL_H_M / 2)
    last = None
    for side in (1.0, -1.0):
        along = h.along_m + side * right_along * (outer[0] / 2 + LABEL_GAP_M + LABEL_W_M / 2)
        try:
            item = _wall_item(ex, p.key, f"the label of {p.title!r}", h.wall, w, along,
                              centre_h, LABEL_W_M, LABEL_H_M, wall_h)
            break
        except ExhibitionError as e:
            last = e
    else:
        raise last
    items.append(item)
    centre = np.array([w.a[0], centre_h, w.a[1]]) + w.t * along
    origin = centre + w.n * WALL_GAP_M - u * (LABEL_W_M / 2) + np.array([0.0, LABEL_H_M / 2, 0.0])
    name = f"label-{p.name}"
    return PaintingSlot(name, tuple(float(x) for x in origin), tuple(float(x) for x in u),
                        (0.0, -1.0, 0.0), LABEL_W_M, LABEL_H_M, name=name)


def _check_overlaps(ex, items: list[_Item], walls: list[Wall]) -> None:
    for k, a in enumerate(items):
        for b in items[:k]:
            if a.wall == b.wall and a.lo < b.hi - 1e-9 and b.lo < a.hi - 1e-9 \
                    and a.bottom < b.top - 1e-9 and b.bottom < a.top - 1e-9:
                raise ExhibitionError(
                    f"{ex.path}: {a.key}.hang: expected {a.what} ({a.hi - a.lo:.4g} m x "
                    f"{a.top - a.bottom:.4g} m at {a.lo:.4g}..{a.hi:.4g} m along wall {a.wall}) "
                    f"to overlap nothing; it overlaps {b.what} of {b.key} ({b.hi - b.lo:.4g} m "
                    f"x {b.top - b.bottom:.4g} m at {b.lo:.4g}..{b.hi:.4g} m)")


def table_axes(h):
    """(u, v, toward the visitor) of a table painting: u the visitor's right, v image down."""
    th, tilt = math.radians(h.facing_deg), math.radians(h.tilt_deg)
    u = np.array([math.cos(th), 0.0, -math.sin(th)])
    back = np.array([math.sin(th), 0.0, math.cos(th)])
    v = -math.sin(tilt) * np.array([0.0, 1.0, 0.0]) + math.cos(tilt) * back
    return u, v, back


def _table_slot(ex, p, poly, footprints: list):
    from shapely.geometry import Polygon
    h = p.hang
    u, v, back = table_axes(h)
    centre = np.array([h.position_m[0], h.height_m, h.position_m[1]])
    origin = centre - u * p.width_m / 2 - v * p.height_m / 2
    slot = PaintingSlot(pack_name(p), tuple(float(x) for x in origin), tuple(float(x) for x in u),
                        tuple(float(x) for x in v), p.width_m, p.height_m, name=p.name)
    depth = p.height_m * math.cos(math.radians(h.tilt_deg))
    hw, hd = p.width_m / 2 + TABLE_MARGIN_M, depth / 2 + TABLE_MARGIN_M
    top = h.height_m - p.height_m / 2 * math.sin(math.radians(h.tilt_deg)) - 1e-3
    if top < 0.05:
        raise ExhibitionError(f"{ex.path}: {p.key}.hang.height_cm: expected the painting "
                              f"({p.width_m:.4g} m x {p.height_m:.4g} m, tilted "
                              f"{h.tilt_deg:g} deg) to clear the floor; its lowest edge is at "
                              f"{top + 1e-3:.4g} m")
    c2 = np.array([h.position_m[0], h.position_m[1]])
    ux, bx = np.array([u[0], u[2]]), np.array([back[0], back[2]])
    corners = [c2 + sx * hw * ux + sz * hd * bx for sx, sz in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    foot = Polygon(corners)
    if not poly.buffer(1e-9).contains(foot):
        raise ExhibitionError(f"{ex.path}: {p.key}.hang.position_m: expected the {h.on} "
                              f"({2 * hw:.4g} m x {2 * hd:.4g} m) inside the floor plan "
                              f"({poly.bounds[2] - poly.bounds[0]:.4g} m x "
                              f"{poly.bounds[3] - poly.bounds[1]:.4g} m)")
    for key, other in footprints:
        if foot.intersection(other).area > 1e-9:
            raise ExhibitionError(f"{ex.path}: {p.key}.hang.position_m: expected the {h.on} "
                                  f"({2 * hw:.4g} m x {2 * hd:.4g} m) to overlap nothing; it "
                                  f"overlaps the one of {key}")
    footprints.append((p.key, foot))
    box_c = np.array([c2[0], top / 2, c2[1]])
    quads = _oriented_box(box_c, (u, np.array([0.0, 1.0, 0.0]), back), (hw, top / 2, hd))
    return slot, quads


def _default_lights(ex, walls, height) -> list[LightSpec]:
    """One light per painting, solved for the file's `lux` (default 200): a row of SPOT_SIZE_M panels at most
    PANEL_SPAN_M apart along the painting's width (one for a painting up to that wide), each
    over the middle of its share of the painting, 30 degrees off vertical from it, so a long
    scroll is lit along its length rather than by one spot at its centre. The panels face
    down, as ceiling fixtures do: a panel tilted toward the wall would light the ceiling a
    few centimetres away, a hot patch whose light the bake's final gather turns into
    sparkles all over the room."""
    lights, y = [], height - 0.1
    for p in ex.paintings:
        h = p.hang
        if h.wall is not None:
            w = walls[h.wall]
            face = WALL_GAP_M + (p.frame.depth_m if p.frame else 0.0)  # the painting's plane
            centre = (np.array([w.a[0], h.centre_height_m, w.a[1]]) + w.t * h.along_m
                      + w.n * face)
            setback = max(0.3, (y - h.centre_height_m) * math.tan(math.radians(SPOT_AIM_DEG)))
            lift, along = w.n * setback + np.array([0.0, y - h.centre_height_m, 0.0]), w.t
        else:
            centre = np.array([h.position_m[0], h.height_m, h.position_m[1]])
            lift, along = np.array([0.0, y - h.height_m, 0.0]), table_axes(h)[0]
        n = max(1, math.ceil(p.width_m / PANEL_SPAN_M - 1e-9))
        panels = []
        for k in range(n):
            aim_at = centre + along * (p.width_m * ((k + 0.5) / n - 0.5))
            panels.append(rectangle(aim_at + lift, DOWN, SPOT_SIZE_M, SPOT_SIZE_M))
        lights.append(LightSpec(f"light-{p.name}", panels, lux=ex.lux, painting=p.name))
    return lights


def _suggested_view(ex, slots, poly):
    """The room's suggested camera: the plan's centroid at 1.6 m, toward the first painting."""
    c = poly.representative_point() if not poly.contains(poly.centroid) else poly.centroid
    s = slots[0]
    target = (np.array(s.origin) + 0.5 * s.width_m * np.array(s.u_axis)
              + 0.5 * s.height_m * np.array(s.v_axis))
    return (float(c.x), 1.6, float(c.y)), tuple(float(x) for x in target)

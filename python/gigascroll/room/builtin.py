"""The built-in rooms of the gallery, as `RoomSpec`s: `scroll` (VT-mobile-VR §5.3) and `hall`
(section 5.4). Every dimension, albedo and light is written down here.

Units: lengths in metres, y up. Emission is radiance in W / m^2 / sr per RGB channel, linear,
white lights (equal channels). Illuminance targets are given in "lux equivalent": irradiance
in W / m^2 per channel times 683 lm / W (the lumen's definition at 555 nm), so a gallery's
200 lux is 200 / 683 = 0.293 W / m^2 per channel. The light radiances are solved so that the
*direct* illuminance on the paintings (from the lights alone, computed exactly with Lambert's
polygon formula) meets the target; interreflections add to it (tens of percent in these rooms),
as they would in a real gallery. Each room's lights are `LightSpec`s (room/lights.py: panels,
colour temperature, lumens or a lux target) that a caller may replace. A display of these
rooms needs an exposure: a painting of
albedo 0.5 under 200 lux eq. has radiance 0.5 * 0.293 / pi = 0.047.

Paintings sit exactly where the scenarios' `ExhibitionScene`s put them
(`gigascroll.views.exhibition.single_scroll` and `multi_exhibition`): the same origin, u and v
axes, and the tables are the same boxes as `ExhibitionScene.add_table`. The one difference is
size: a slot takes the shape of the pack's painting (its aspect ratio), so a painting given with
a physical size (`PaintingSpec`) keeps it, and one given in texels gets the scroll's length
(`scroll`) or the scroll's texel size (`hall`, as `spec_of` does).

Orientation: image x runs along u and image y (down) along v. With the project's camera
(right = forward x up), the image reads unmirrored from the side v x u points to. The hall's
paintings (u = +x, v = +z) face up, v x u = +y, and read upright to a visitor on their +z side
(looking toward -z; the hall's suggested camera stands there). The scroll's placement (origin at x = length,
u = -x, v = -y, as in `single_scroll`) faces the room, v x u = -z: it reads unmirrored from
z < 0, where the visitors stand.
"""

from __future__ import annotations

import math

import numpy as np

from ..views.exhibition import TEXEL_M
from .lights import LightSpec, light_surface
from .lights import LIGHT_ALBEDO  # noqa: F401  (a room's light panels, as before)
from .polygon import polygon_irradiance, unit_irradiance
from .spec import PaintingSlot, RoomSpec, Surface
from .sizes import PaintingSize, painting_sizes

__all__ = ["ROOM_NAMES", "builtin_room", "scroll_room", "hall_room", "LUMENS_PER_WATT",
           "GALLERY_LUX", "lux_to_irradiance", "polygon_irradiance", "unit_irradiance",
           "direct_irradiance",
           "emitted_power"]

ROOM_NAMES = ("scroll", "hall")

LUMENS_PER_WATT = 683.0   # lux equivalent per W / m^2 (see the module docstring)
GALLERY_LUX = 200.0       # target direct illuminance on the paintings (museums: 50..300 lux)

# Albedos (linear RGB, all < 1): painted plaster walls, a pale ceiling, an oak floor, dark
# stained table wood, and the diffusers of the light panels.
WALL_ALBEDO = (0.80, 0.78, 0.74)
CEILING_ALBEDO = (0.85, 0.85, 0.85)
FLOOR_ALBEDO = (0.35, 0.27, 0.20)
TABLE_ALBEDO = (0.25, 0.20, 0.16)

# --- scroll (VT-mobile-VR §5.3) -----------------------------------------------------------
SCROLL_LENGTH_M = 12.0        # the seed's 12 m scroll
SCROLL_CENTRE_HEIGHT = 1.5    # eye height, single_scroll's default
SCROLL_MAX_HEIGHT = 1.6       # a painting taller than this (at 12 m) is shrunk to it
SCROLL_WALL_Z = 0.005         # single_scroll's wall box starts 5 mm behind the painting plane
SCROLL_MARGIN_X = 2.0         # wall beyond each end of the scroll (single_scroll's wall box)
SCROLL_ROOM_DEPTH = 4.0       # from the wall to the opposite wall (single_scroll's floor)
SCROLL_CEILING = 3.0          # single_scroll's wall height
SPOT_SIZE = 0.30              # square panel lights, side in metres
SPOT_HEIGHT = 2.90            # panel centres, 10 cm below the ceiling (a lighting track)
SPOT_AIM_DEG = 30.0           # the gallery "30 degree rule": aimed 30 degrees off vertical
SPOT_SPACING = 1.5            # about one panel per 1.5 m of scroll
SPOT_LUX = 180.0              # mean direct illuminance the panels give the scroll
FILL_LUX = 20.0               # direct illuminance the dim ceiling fill gives its centre
FILL_INSET = 1.0              # the fill panel keeps 1 m from the side walls and the front wall
FILL_BACK = 1.5               # and 1.5 m from the back wall (the spots hang there)

# --- hall (VT-mobile-VR §5.4) -------------------------------------------------------------
TABLE_HEIGHT = 0.70           # multi_exhibition's tables
TABLE_GAP = 0.10              # multi_exhibition's margin between paintings and table edges
TABLE_TOP = 0.04              # ExhibitionScene.add_table: top thickness and leg width
TABLE_LEG = 0.06
TABLE_SPACING = 1.0           # aisle between tables (along z)
PAINTING_LIFT = 0.001         # paintings lie 1 mm above the table top
HALL_MARGIN = 5.0             # floor around the tables (multi_exhibition's floor box)
HALL_FIRST_TABLE_Z = 1.0      # the first table starts at z = 1 m
HALL_CEILING = 4.0
HALL_PANEL_SIZE = 0.60        # square ceiling panels, 2 cm below the ceiling, facing down
HALL_PANEL_DROP = 0.02
HALL_PANEL_SPACING = 2.0      # about one panel per 2 m x 2 m of table
HALL_MAX_TABLES = 5           # 40 Table 4 paintings


def lux_to_irradiance(lux: float) -> float:
    """Irradiance in W / m^2 per channel for an illuminance in lux equivalent."""
    return lux / LUMENS_PER_WATT


def direct_irradiance(spec: RoomSpec, point, normal) -> np.ndarray:
    """Unoccluded direct irradiance (W / m^2 per channel) at a point from every emitting quad of
    the room (each emitter is a list of quads: triangles 2k, 2k+1 share corners)."""
    e = np.zeros(3)
    for s in spec.surfaces:
        if max(s.emission) <= 0:
            continue
        e += unit_irradiance([point], normal, _quads_of(s)).sum() * np.asarray(s.emission)
    return e


def emitted_power(spec: RoomSpec) -> np.ndarray:
    """Total emitted power (W per channel) of one-sided Lambertian emitters: pi * area * L."""
    power = np.zeros(3)
    for s in spec.surfaces:
        t = s.vertices[s.triangles]
        area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
        power += math.pi * area * np.asarray(s.emission)
    return power


def builtin_room(name: str, paintings, count: int | None = None, lights=None) -> RoomSpec:
    """The built-in room `name` (one of ROOM_NAMES) for these paintings (a TilePack, a list of
    PaintingSpecs, or see `painting_sizes`). `count`: the number of paintings in the hall (a
    positive multiple of the number of paintings, at most HALL_MAX_TABLES tables); the scroll
    room shows one painting, the first. `lights`: a list of `LightSpec`s in place of the
    room's own (None: the room's lights, described in its function)."""
    if name == "scroll":
        if count not in (None, 1):
            raise ValueError(f"the scroll room shows one painting, got count={count}")
        return scroll_room(paintings, lights=lights)
    if name == "hall":
        return hall_room(paintings, count, lights=lights)
    raise ValueError(f"unknown room {name!r}; built-in rooms: {', '.join(ROOM_NAMES)}")


# --- geometry helpers ------------------------------------------------------------------------

def _quad(centre, half_a, half_b, front) -> np.ndarray:
    """The 4 corners of a rectangle, counter-clockwise seen from the side `front` points to."""
    c, a, b = (np.asarray(x, dtype=np.float64) for x in (centre, half_a, half_b))
    corners = np.array([c - a - b, c + a - b, c + a + b, c - a + b])
    if np.dot(np.cross(a, b), front) < 0:
        corners = corners[::-1].copy()
    return corners


def _surface(name: str, quads: list[np.ndarray], albedo, emission=(0.0, 0.0, 0.0)) -> Surface:
    """A surface of quads: quad k has vertices 4k..4k+3 and triangles 2k, 2k+1."""
    vertices = np.concatenate(quads).astype(np.float64)
    base = 4 * np.arange(len(quads), dtype=np.int64)[:, None]
    triangles = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(-1, 3)
    return Surface(name, vertices, triangles, tuple(float(x) for x in albedo),
                   tuple(float(x) for x in emission))


def _quads_of(surface: Surface) -> list[np.ndarray]:
    """The quads of a surface made by _surface."""
    return [surface.vertices[4 * k:4 * k + 4] for k in range(len(surface.triangles) // 2)]


def _box_quads(lo, hi) -> list[np.ndarray]:
    """The six faces of an axis-aligned box, facing out."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, (hi - lo) / 2
    quads = []
    for axis in range(3):
        a, b = [np.eye(3)[i] * h[i] for i in range(3) if i != axis]
        for sign in (-1.0, 1.0):
            n = np.eye(3)[axis] * sign
            quads.append(_quad(c + n * h[axis], a, b, n))
    return quads


def _shell(lo, hi) -> list[Surface]:
    """A closed room: floor, ceiling and walls of the box lo..hi, facing in."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    c, h = (lo + hi) / 2, (hi - lo) / 2
    ex, ey, ez = np.eye(3)
    floor = _quad(c - ey * h[1], ex * h[0], ez * h[2], ey)
    ceiling = _quad(c + ey * h[1], ex * h[0], ez * h[2], -ey)
    walls = [_quad(c + ex * s * h[0], ey * h[1], ez * h[2], -s * ex) for s in (-1, 1)]
    walls += [_quad(c + ez * s * h[2], ex * h[0], ey * h[1], -s * ez) for s in (-1, 1)]
    return [_surface("floor", [floor], FLOOR_ALBEDO), _surface("ceiling", [ceiling], CEILING_ALBEDO),
            _surface("walls", walls, WALL_ALBEDO)]


def _size_m(p: PaintingSize, width_m: float) -> tuple[float, float]:
    """Physical size: the painting's own when given, else width_m wide at its aspect."""
    if p.width_m is not None and p.height_m is not None:
        return p.width_m, p.height_m
    return width_m, width_m / p.aspect


# --- the rooms -------------------------------------------------------------------------------

def scroll_room(paintings, painting: int | str = 0, lights=None) -> RoomSpec:
    """VT-mobile-VR §5.3: one scroll on a wall at eye height, the room sized to it.

    The painting (default the first) is 12 m long at its own aspect (or its physical size when
    given), centred at 1.5 m, in the plane z = 0 from x = 0 to its length, 5 mm in front of the
    back wall, origin/u/v as in `single_scroll`. Room: x from -2 m to length + 2 m, y from 0 to
    3 m, z from -4 m to the wall. Lights: a row of 0.3 m square panels, one per ~1.5 m of scroll,
    on a track 10 cm below the ceiling, each aimed at the scroll's centre line at 30 degrees off
    vertical, giving the scroll 180 lux eq. of direct light on average; plus a dim fill panel
    over the middle of the ceiling (1 m from the side and front walls, 1.5 m from the back
    wall) giving the scroll's centre 20 lux eq. (Both white `LightSpec`s; `lights` replaces
    them.)
    """
    sizes = painting_sizes(paintings)
    index = _painting_index(sizes, painting)
    p = sizes[index]
    width, height = _size_m(p, SCROLL_LENGTH_M)
    if p.width_m is None and height > SCROLL_MAX_HEIGHT:
        width, height = SCROLL_MAX_HEIGHT * p.aspect, SCROLL_MAX_HEIGHT
    _check_size(width, height, p.name, max_width=100.0, max_height=2.5)
    centre = SCROLL_CENTRE_HEIGHT
    top = centre + height / 2
    # Texel (0, 0) top-left as seen from the room (z < 0): image x runs along -x.
    slot = PaintingSlot(index, (width, top, 0.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), width, height,
                        name=p.name)

    lo = np.array([-SCROLL_MARGIN_X, 0.0, SCROLL_WALL_Z - SCROLL_ROOM_DEPTH])
    hi = np.array([width + SCROLL_MARGIN_X, SCROLL_CEILING, SCROLL_WALL_Z])
    surfaces = _shell(lo, hi)

    # The spot row: panel k centred over x_k, at the distance from the wall that aims it 30
    # degrees off vertical at the centre line.
    n_spots = max(1, round(width / SPOT_SPACING))
    setback = (SPOT_HEIGHT - centre) * math.tan(math.radians(SPOT_AIM_DEG))
    spots = []
    for k in range(n_spots):
        x = (k + 0.5) * width / n_spots
        c = np.array([x, SPOT_HEIGHT, -setback])
        aim = np.array([x, centre, 0.0]) - c
        aim /= np.linalg.norm(aim)
        side = np.cross(aim, [1.0, 0.0, 0.0])
        spots.append(_quad(c, [SPOT_SIZE / 2, 0, 0], side / np.linalg.norm(side) * SPOT_SIZE / 2,
                           aim))
    # Receivers: a grid over the painting (its front faces the room, -z).
    face = np.array([0.0, 0.0, -1.0])
    xs = np.linspace(0.0, width, 4 * n_spots + 1)
    ys = np.linspace(top - height, top, 3)
    grid = [(x, y, 0.0) for x in xs for y in ys]
    fill_x = (lo[0] + FILL_INSET, hi[0] - FILL_INSET)
    fill_z = (lo[2] + FILL_INSET, hi[2] - FILL_BACK)
    fill = _quad([sum(fill_x) / 2, SCROLL_CEILING - 0.01, sum(fill_z) / 2],
                 [(fill_x[1] - fill_x[0]) / 2, 0, 0], [0, 0, (fill_z[1] - fill_z[0]) / 2],
                 [0.0, -1.0, 0.0])
    if lights is None:
        lights = [LightSpec("spot_lights", spots, lux=SPOT_LUX, points=grid, normal=face),
                  LightSpec("fill_light", [fill], lux=FILL_LUX, points=[(width / 2, centre, 0.0)],
                            normal=face)]
    surfaces += [light_surface(light, [slot]) for light in lights]
    return RoomSpec("scroll", surfaces, [slot], camera_eye=(width / 2, 1.6, -3.0),
                    camera_target=(width / 2, centre, 0.0), lights=list(lights))


def hall_room(paintings, count: int | None = None, texel_m: float = TEXEL_M,
              lights=None) -> RoomSpec:
    """VT-mobile-VR §5.4: `count` paintings (default: one of each) laid flat on 70 cm tables,
    as `multi_exhibition` lays them: painting slot i shows painting i % n; eight (n) to a table,
    side by side across it, long side along x, 1 mm above the top; table g runs along x at z
    from 1 + g * (depth + 1) m. A painting given in texels is texel_m metres per texel (the
    scroll's texel size, as `spec_of`). Tables are boxes: a 4 cm top and four 6 cm legs. Room:
    5 m of floor around the tables, 4 m ceiling. Lights: 0.6 m square ceiling panels facing
    down, 2 cm below the ceiling, a grid of about one per 2 m x 2 m over each table, giving the
    paintings' centres 200 lux eq. of direct light on average (one white `LightSpec`;
    `lights` replaces it).
    """
    sizes = painting_sizes(paintings)
    n = len(sizes)
    count = n if count is None else count
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1 \
            or count % n or count // n > HALL_MAX_TABLES:
        raise ValueError(f"hall: count must be a positive multiple of {n} (the number of "
                         f"paintings) and at most {HALL_MAX_TABLES * n}, got {count!r}")
    gap = TABLE_GAP
    dims = []
    for p in sizes:
        w, h = _size_m(p, p.width * texel_m)
        _check_size(w, h, p.name, max_width=50.0, max_height=20.0)
        dims.append((w, h))
    length = max(0.3, max(w for w, _ in dims) + 2 * gap)
    depth = max(0.3, sum(h for _, h in dims) + (n + 1) * gap)
    tables = count // n
    slots, table_quads, panels, centres = [], [], [], []
    for g in range(tables):
        z0 = HALL_FIRST_TABLE_Z + g * (depth + TABLE_SPACING)
        table_quads += _table_quads(length / 2, z0 + depth / 2, length, depth, TABLE_HEIGHT)
        z = z0 + gap
        for i, (p, (w, h)) in enumerate(zip(sizes, dims)):
            slots.append(PaintingSlot(i, (gap, TABLE_HEIGHT + PAINTING_LIFT, z), (1.0, 0.0, 0.0),
                                      (0.0, 0.0, 1.0), w, h, name=f"table{g}_{p.name}"))
            centres.append((gap + w / 2, TABLE_HEIGHT + PAINTING_LIFT, z + h / 2))
            z += h + gap
        nx = max(1, round(length / HALL_PANEL_SPACING))
        nz = max(1, round(depth / HALL_PANEL_SPACING))
        for ix in range(nx):
            for iz in range(nz):
                c = [(ix + 0.5) * length / nx, HALL_CEILING - HALL_PANEL_DROP,
                     z0 + (iz + 0.5) * depth / nz]
                panels.append(_quad(c, [HALL_PANEL_SIZE / 2, 0, 0], [0, 0, HALL_PANEL_SIZE / 2],
                                    [0.0, -1.0, 0.0]))
    z_end = HALL_FIRST_TABLE_Z + tables * (depth + TABLE_SPACING) - TABLE_SPACING
    lo = np.array([-HALL_MARGIN, 0.0, HALL_FIRST_TABLE_Z - 1.0 - HALL_MARGIN])
    hi = np.array([length + HALL_MARGIN, HALL_CEILING, z_end + HALL_MARGIN])
    surfaces = _shell(lo, hi)
    surfaces.append(_surface("tables", table_quads, TABLE_ALBEDO))
    if lights is None:
        lights = [LightSpec("ceiling_lights", panels, lux=GALLERY_LUX, points=centres,
                            normal=[0.0, 1.0, 0.0])]
    surfaces += [light_surface(light, slots) for light in lights]
    # The suggested camera stands beyond the last table's far edge (+z), where the paintings'
    # bottoms are: image y (down) runs along +z, so only from there do they read upright
    # (from the -z side they read rotated by 180 degrees).
    return RoomSpec("hall", surfaces, slots, camera_eye=(length / 2, 1.7, z_end + 3.5),
                    camera_target=(length / 2, TABLE_HEIGHT, z_end - depth / 2), lights=list(lights))


def _table_quads(x, z, length, depth, height) -> list[np.ndarray]:
    """ExhibitionScene.add_table as boxes: the top and four legs."""
    hl, hd, top, leg = length / 2, depth / 2, TABLE_TOP, TABLE_LEG
    quads = _box_quads((x - hl, height - top, z - hd), (x + hl, height, z + hd))
    for sx in (-1, 1):
        for sz in (-1, 1):
            cx, cz = x + sx * (hl - leg), z + sz * (hd - leg)
            quads += _box_quads((cx - leg / 2, 0.0, cz - leg / 2),
                                (cx + leg / 2, height - top, cz + leg / 2))
    return quads


def _painting_index(sizes: list[PaintingSize], painting: int | str) -> int:
    if isinstance(painting, str):
        for i, p in enumerate(sizes):
            if p.name == painting:
                return i
        raise ValueError(f"no painting named {painting!r}")
    if not 0 <= painting < len(sizes):
        raise ValueError(f"painting index {painting} out of range (0..{len(sizes) - 1})")
    return int(painting)


def _check_size(width: float, height: float, name: str, max_width: float, max_height: float):
    if not (0.001 <= width <= max_width and 0.001 <= height <= max_height):
        raise ValueError(f"painting {name!r}: {width:.4g} m x {height:.4g} m does not fit the room "
                         f"(1 mm .. {max_width:g} m x {max_height:g} m)")

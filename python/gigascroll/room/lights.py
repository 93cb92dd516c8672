"""The gallery's lights as a lighting designer gives them: `LightSpec`.

A light is one or more rectangular panels (diffusers: one-sided Lambertian emitters) that share
a colour and an intensity. Its colour is a colour temperature in kelvin (the Planckian
radiator, `light_colour.kelvin_to_rgb`; None: white, equal linear sRGB channels, sRGB's D65
white). Its intensity is either

- a luminous flux in lumens (a lamp's datasheet figure) for all its panels together:
  flux = 683 lm/W x pi x area x L for a Lambertian panel of radiance L at unit luminance; or
- a target illuminance in lux: the mean *direct* illuminance over a painting slot (its
  slot_grid points) or over given points, for which the radiance is solved exactly. The direct
  illuminance is linear in the radiance, and Lambert's polygon formula (room/polygon.py)
  gives it for unit radiance with nothing in between. Interreflections add to it (tens of
  percent in a pale room; nothing with black walls), as they would in a real gallery; the
  `light` command measures the total.

`light_surface(light, slots)` turns a spec into the room's emitting `Surface` (emission =
L x the colour's linear sRGB at unit luminance). `rectangle(centre, aim, width, height)`
makes a panel's corners; `lights_from_json` reads a list of specs (the `light` command's
`--lights` file).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .light_colour import LUMINANCE_WEIGHTS, kelvin_to_rgb
from .polygon import unit_irradiance
from .spec import PaintingSlot, Surface
from .slot_grid import slot_front, slot_points

__all__ = ["LightSpec", "LIGHT_ALBEDO", "SOLVE_SAMPLES", "rectangle", "light_surface",
           "light_colour", "solve_radiance", "panels_irradiance", "lights_from_json",
           "light_from_extras", "load_lights"]

LUMENS_PER_WATT = 683.0   # as room/builtin.py: lux equivalent per W / m^2
LIGHT_ALBEDO = (0.70, 0.70, 0.70)  # a light panel's diffuser
SOLVE_SAMPLES = 64        # slot_grid cells along a painting's longer side for a target solve
MAX_EXTENT_M = 10_000.0
MAX_LUMENS = 1e9
MAX_LUX = 1e6
MAX_PANELS = 100_000


@dataclass
class LightSpec:
    """One light: `panels` (a list of planar convex polygons, (K, 3) corner arrays with
    3 <= K <= 16, counter-clockwise seen from the lit side: rectangles, or a room file's
    triangles), `kelvin` (None: white), and exactly one of `lumens` (total luminous flux) or
    `lux` (the target mean direct illuminance on `painting`: a slot's name, its painting's
    name, or the slot's index; or else at `points` (P, 3) facing `normal`)."""

    name: str
    panels: list
    kelvin: float | None = None
    lumens: float | None = None
    lux: float | None = None
    painting: str | int | None = None
    points: object = None
    normal: object = None
    albedo: tuple = LIGHT_ALBEDO
    details: dict = field(default_factory=dict)  # what the solve found (radiance, lumens)


def rectangle(centre, aim, width: float, height: float, across=(1.0, 0.0, 0.0)) -> np.ndarray:
    """A panel's 4 corners: centred at `centre`, emitting toward `aim`, `width` metres along
    `across` (made perpendicular to aim; world z when across is parallel to it) and `height`
    along aim x across; counter-clockwise seen from the lit side."""
    c, a = _vec(centre, "centre"), _unit(aim, "aim")
    x = _vec(across, "across")
    x = x - (x @ a) * a
    if np.linalg.norm(x) < 1e-9:
        x = np.array([0.0, 0.0, 1.0]) - a[2] * a
    x /= np.linalg.norm(x)
    y = np.cross(a, x)
    y /= np.linalg.norm(y)
    w, h = (_positive(v, what, MAX_EXTENT_M) for v, what in ((width, "width"), (height, "height")))
    half_a, half_b = x * w / 2, y * h / 2
    corners = np.array([c - half_a - half_b, c + half_a - half_b, c + half_a + half_b,
                        c - half_a + half_b])
    if np.dot(np.cross(half_a, half_b), a) < 0:
        corners = corners[::-1].copy()
    return corners


def light_colour(light: LightSpec) -> np.ndarray:
    """The light's linear sRGB at unit luminance."""
    return np.ones(3) if light.kelvin is None else np.array(kelvin_to_rgb(light.kelvin))


def solve_radiance(light: LightSpec, slots: list[PaintingSlot]) -> float:
    """The radiance scale L (W / m^2 / sr at unit luminance) that gives the spec's lumens or
    its target lux; ValueError for a spec that is not one of the documented forms."""
    panels = _panels(light)
    if (light.lumens is None) == (light.lux is None):
        raise ValueError(f"light {light.name!r}: give exactly one of lumens or lux")
    if light.lumens is not None:
        lumens = _positive(light.lumens, f"light {light.name!r}: lumens", MAX_LUMENS)
        return lumens / (LUMENS_PER_WATT * math.pi * sum(_area(q) for q in panels))
    lux = _positive(light.lux, f"light {light.name!r}: lux", MAX_LUX)
    points, normal = _receivers(light, slots)
    try:
        unit = panels_irradiance(points, normal, panels).mean()
    except ValueError:
        raise ValueError(f"light {light.name!r}: a panel crosses the plane of the points it "
                         "lights (it must lie wholly in front of them)") from None
    if not unit > 0:
        raise ValueError(f"light {light.name!r}: no panel faces the points it should light")
    return lux / LUMENS_PER_WATT / float(unit)


def panels_irradiance(points, normal, panels) -> np.ndarray:
    """The unit-radiance irradiance (P,) at the points from all the panels (Lambert's
    formula, the panels grouped by their number of corners)."""
    p = np.asarray(points, np.float64).reshape(-1, 3)
    total = np.zeros(len(p))
    for k in sorted({len(q) for q in panels}):
        total += unit_irradiance(p, normal, [q for q in panels if len(q) == k]).sum(axis=1)
    return total


def light_surface(light: LightSpec, slots: list[PaintingSlot]) -> Surface:
    """The room's emitting surface for `light`: its panels fanned into triangles (a
    rectangle's are 2k, 2k + 1), emission = solve_radiance x light_colour. Records radiance,
    colour, lumens and area in light.details."""
    panels = _panels(light)
    radiance = solve_radiance(light, slots)
    rgb = light_colour(light)
    vertices = np.concatenate(panels).astype(np.float64)
    starts = np.cumsum([0] + [len(q) for q in panels[:-1]])
    triangles = np.array([[s0, s0 + j, s0 + j + 1] for s0, q in zip(starts, panels)
                          for j in range(1, len(q) - 1)], dtype=np.int64)
    area = sum(_area(q) for q in panels)
    light.details = {"radiance": float(radiance), "rgb": rgb.tolist(),
                     "lumens": float(LUMENS_PER_WATT * math.pi * area * radiance
                                     * float(rgb @ np.asarray(LUMINANCE_WEIGHTS))),
                     "area_m2": float(area)}
    return Surface(light.name, vertices, triangles, tuple(float(a) for a in light.albedo),
                   tuple(float(radiance * c) for c in rgb))


# --- reading specs -----------------------------------------------------------------------------

_KEYS = {"name", "centre", "aim", "width", "height", "across", "kelvin", "lumens", "lux",
         "painting", "panels"}
_PANEL_KEYS = {"centre", "aim", "width", "height", "across"}


def lights_from_json(data) -> list[LightSpec]:
    """Light specs from JSON data: a list of objects with name, centre [x, y, z], aim
    [x, y, z], width and height (metres), optional across [x, y, z] (or instead "panels": a
    list of such {centre, aim, width, height[, across]}, lit together), kelvin, and lumens or
    lux with painting (a slot's name, its painting's name, or its index)."""
    if not isinstance(data, list) or not data or len(data) > 1000:
        raise ValueError("lights: expected a list of 1 to 1000 light objects")
    lights = []
    for i, item in enumerate(data):
        if not isinstance(item, dict):
            raise ValueError(f"lights[{i}]: expected an object, got {type(item).__name__}")
        unknown = set(item) - _KEYS
        if unknown:
            raise ValueError(f"lights[{i}]: unknown keys {sorted(unknown)[:5]} (known: "
                             f"{', '.join(sorted(_KEYS))})")
        name = item.get("name", f"light{i}")
        if not isinstance(name, str) or not 0 < len(name) <= 200:
            raise ValueError(f"lights[{i}]: name must be a string of 1 to 200 characters")
        if "lux" in item and "painting" not in item:
            raise ValueError(f"light {name!r}: lux needs the painting it is measured on")
        panels = [_json_panel(p, f"light {name!r}: panel {k}")
                  for k, p in enumerate(_json_panels(item, name))]
        painting = item.get("painting")
        if painting is not None and (isinstance(painting, bool)
                                     or not isinstance(painting, (str, int))):
            raise ValueError(f"light {name!r}: painting must be a slot's name or index")
        lights.append(LightSpec(name, panels, kelvin=item.get("kelvin"),
                                lumens=item.get("lumens"), lux=item.get("lux"),
                                painting=painting))
    return lights


def _json_panels(item: dict, name: str) -> list:
    """The panel objects of a light: its "panels", or the light object itself."""
    if "panels" not in item:
        return [{k: v for k, v in item.items() if k in _PANEL_KEYS}]
    if set(item) & _PANEL_KEYS:
        raise ValueError(f"light {name!r}: give panels or one panel's centre, aim, width and "
                         "height, not both")
    panels = item["panels"]
    if not isinstance(panels, list) or not 1 <= len(panels) <= MAX_PANELS:
        raise ValueError(f"light {name!r}: panels must be a list of 1 to {MAX_PANELS} objects")
    return panels


def _json_panel(p, what: str) -> np.ndarray:
    if not isinstance(p, dict):
        raise ValueError(f"{what}: expected an object")
    unknown, missing = set(p) - _PANEL_KEYS, {"centre", "aim", "width", "height"} - set(p)
    if unknown or missing:
        raise ValueError(f"{what}: " + (f"unknown keys {sorted(map(str, unknown))[:5]}"
                                         if unknown else f"missing {', '.join(sorted(missing))}"))
    try:
        return rectangle(p["centre"], p["aim"], p["width"], p["height"],
                         p.get("across", (1.0, 0.0, 0.0)))
    except ValueError as e:
        raise ValueError(f"{what}: {e}") from None


_EXTRAS_KEYS = {"kelvin", "lumens", "lux", "painting"}


def light_from_extras(name: str, panels: list, extras, albedo) -> LightSpec:
    """The LightSpec of a room file's light node: its triangles (or polygons) as panels, its
    material's albedo, and from its glTF extras "light" {kelvin, lumens | lux + painting}."""
    if not isinstance(extras, dict):
        raise ValueError(f"light node {name!r}: extras.light must be an object")
    unknown = set(extras) - _EXTRAS_KEYS
    if unknown:
        raise ValueError(f"light node {name!r}: unknown keys {sorted(map(str, unknown))[:5]} in "
                         f"extras.light (known: {', '.join(sorted(_EXTRAS_KEYS))})")
    painting = extras.get("painting")
    if painting is not None and (isinstance(painting, bool) or not isinstance(painting, (str, int))):
        raise ValueError(f"light node {name!r}: painting must be a name or an index")
    return LightSpec(name, list(panels), kelvin=extras.get("kelvin"), lumens=extras.get("lumens"),
                     lux=extras.get("lux"), painting=painting, albedo=tuple(albedo))


def load_lights(path) -> list[LightSpec]:
    """lights_from_json of a JSON file (at most 1 MB)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such lights file")
    if path.stat().st_size > 1 << 20:
        raise ValueError(f"{path}: a lights file is at most 1 MB")
    try:
        data = json.loads(path.read_text(encoding="utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not a JSON lights file ({e})") from None
    try:
        return lights_from_json(data)
    except ValueError as e:
        raise ValueError(f"{path}: {e}") from None


# --- checks ------------------------------------------------------------------------------------

def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


def _vec(value, what: str) -> np.ndarray:
    try:
        a = np.asarray(value, np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be 3 numbers, got {str(value)[:60]!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.abs(a).max() > MAX_EXTENT_M:
        raise ValueError(f"{what} must be 3 finite numbers within {MAX_EXTENT_M:g} m, got "
                         f"{str(value)[:60]!r}")
    return a


def _unit(value, what: str) -> np.ndarray:
    a = _vec(value, what)
    n = np.linalg.norm(a)
    if n < 1e-9:
        raise ValueError(f"{what} must not be zero")
    return a / n


def _positive(value, what: str, most: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{what} must be a number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and 0 < v <= most):
        raise ValueError(f"{what} must be positive and at most {most:g}, got {value!r}")
    return v


def _area(polygon: np.ndarray) -> float:
    """The area of a planar polygon (K, 3)."""
    return 0.5 * float(np.linalg.norm(np.cross(polygon, np.roll(polygon, -1, axis=0)).sum(axis=0)))


def _panels(light: LightSpec) -> list[np.ndarray]:
    """The panels as float64 arrays: each planar and convex with 3 to 16 finite corners."""
    if not isinstance(light, LightSpec):
        raise ValueError(f"a light must be a LightSpec, got {type(light).__name__}")
    if not isinstance(light.panels, (list, tuple)) or not 1 <= len(light.panels) <= MAX_PANELS:
        raise ValueError(f"light {light.name!r}: panels must be a list of 1 to {MAX_PANELS} "
                         "polygons")
    panels = []
    for k, p in enumerate(light.panels):
        try:
            a = np.asarray(p, np.float64)
        except (TypeError, ValueError):
            a = np.zeros((0, 3))
        if a.ndim != 2 or a.shape[1] != 3 or not 3 <= len(a) <= 16 or not np.all(np.isfinite(a)) \
                or np.abs(a).max() > MAX_EXTENT_M:
            raise ValueError(f"light {light.name!r}: panel {k} must be 3 to 16 finite corners "
                             f"(K, 3) within {MAX_EXTENT_M:g} m")
        n = np.cross(a, np.roll(a, -1, axis=0)).sum(axis=0)
        size = np.ptp(a, axis=0).max()
        if np.linalg.norm(n) < 1e-12 or np.linalg.norm(n) < 1e-9 * size * size:
            raise ValueError(f"light {light.name!r}: panel {k} has no area")
        n /= np.linalg.norm(n)
        turns = np.cross(np.roll(a, -1, axis=0) - a, np.roll(a, -2, axis=0) - np.roll(a, -1, axis=0)) @ n
        if np.abs((a - a[0]) @ n).max() > 1e-6 * size or turns.min() < -1e-9 * size * size:
            raise ValueError(f"light {light.name!r}: panel {k} is not a planar convex polygon")
        panels.append(a)
    return panels


def _receivers(light: LightSpec, slots: list[PaintingSlot]) -> tuple[np.ndarray, np.ndarray]:
    """The points (P, 3) and the normal a lux target is the mean direct illuminance of."""
    if (light.painting is None) == (light.points is None):
        raise ValueError(f"light {light.name!r}: a lux target needs exactly one of painting or "
                         "points")
    if light.points is not None:
        p = np.asarray(light.points, np.float64).reshape(-1, 3)
        if not len(p) or not np.all(np.isfinite(p)):
            raise ValueError(f"light {light.name!r}: points must be finite (P, 3)")
        return p, _unit(light.normal, f"light {light.name!r}: normal")
    which = light.painting
    if isinstance(which, str):  # a slot's own name first, then its painting's
        found = [s for s in slots if s.name == which] or [s for s in slots if s.painting == which]
    elif isinstance(which, (int, np.integer)) and not isinstance(which, bool):
        found = [slots[int(which)]] if 0 <= which < len(slots) else []
    else:
        found = []
    if found:
        return slot_points(found[0], SOLVE_SAMPLES).reshape(-1, 3), slot_front(found[0])
    names = [s.name for s in slots]
    raise ValueError(f"light {light.name!r}: no painting slot {which!r} in the room (slots: "
                     f"{', '.join(map(str, names[:10]))}{' ...' if len(names) > 10 else ''})")

"""A camera in front of one painting (`--look-at TITLE|N [--distance M]`).

The eye stands on the painting's normal through its centre, on the visitor's side, and looks
at the centre, so the painting is centred in the view. A wall painting is seen square on (the
eye at its centre height); a painting lying flat or tilted on a table is seen from its
normal turned 45 degrees toward the visitor's side when it faces up (a camera looking straight
down has no up direction). The default distance makes the painting fill FILL of the view's
width or height (whichever it reaches first) at the vertical field of view `fov` and the
view's aspect (width / height): d = max(w / (2 FILL tan(fov_x / 2)), h / (2 FILL tan(fov / 2))),
but never beyond the room's bounding box (less 5 cm): a long scroll in a shallow room is seen
from as far as the room allows, not from behind its wall. A given distance is taken as is.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["FILL", "look_at", "slot_index", "fill_distance", "room_bounds"]

FILL = 0.8


def slot_index(room, which, titles: dict | None = None) -> int:
    """The index of the room's painting slot named by `which`: an index (int or digits), a
    title in `titles` (title -> pack painting name), a slot's name or its painting's name.
    ValueError listing what exists."""
    slots = room.paintings
    text = str(which).strip()
    if (isinstance(which, int) or text.isdigit()) and titles:  # a show: painting k's slot
        if not 0 <= int(text) < len(titles):
            raise ValueError(f"--look-at {int(text)}: the exhibition has {len(titles)} "
                             f"paintings (0..{len(titles) - 1})")
        which = list(titles)[int(text)]
    elif isinstance(which, int) or text.isdigit():
        k = int(text)
        if not 0 <= k < len(slots):
            raise ValueError(f"--look-at {k}: the room has {len(slots)} paintings "
                             f"(0..{len(slots) - 1})")
        return k
    name = (titles or {}).get(which, which)
    for k, s in enumerate(slots):
        if name in (s.name, s.painting):
            return k
    known = list(titles or {}) or [s.name or str(s.painting) for s in slots]
    raise ValueError(f"--look-at: no painting titled {text[:80]!r} (known: "
                     f"{', '.join(repr(t) for t in known[:12])})")


def fill_distance(width_m: float, height_m: float, fov: float, aspect: float) -> float:
    """The distance at which a width_m x height_m painting fills FILL of the view."""
    ty = math.tan(math.radians(fov) / 2)
    tx = aspect * ty
    return max(width_m / (2 * FILL * tx), height_m / (2 * FILL * ty))


def _fitting_distance(centre, front, corners, fov: float, aspect: float) -> float:
    """The distance along `front` from which the camera, aimed at `centre` (up: +y, as the
    commands' cameras), sees every corner within FILL of the view: fill_distance for a
    painting seen square on, farther for one seen at an angle (on a table), whose near edge
    would otherwise leave the view."""
    ty = math.tan(math.radians(fov) / 2)
    tx = aspect * ty
    fwd = -front
    up = np.array([0.0, 1.0, 0.0]) if abs(fwd[1]) < 0.999 else np.array([0.0, 0.0, -1.0])
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)

    def fits(d: float) -> bool:
        for c in corners:
            p = c - (centre + d * front)
            z = float(p @ fwd)
            if z <= 1e-9 or abs(p @ right) > FILL * tx * z or abs(p @ up) > FILL * ty * z:
                return False
        return True
    size = max(float(np.linalg.norm(c - centre)) for c in corners)
    lo, hi = 0.0, max(size / (FILL * min(tx, ty)), 1e-3)
    while not fits(hi):
        hi *= 2
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    return hi


def room_bounds(room):
    """(lo, hi) corners of the box around the room's surfaces (None without surfaces)."""
    pts = [np.asarray(s.vertices, float).reshape(-1, 3) for s in room.surfaces]
    pts = [p for p in pts if p.size]
    if not pts:
        return None
    allp = np.concatenate(pts)
    return allp.min(axis=0), allp.max(axis=0)


def _inside_distance(centre, direction, bounds) -> float:
    """How far from `centre` along `direction` the box `bounds` ends."""
    lo, hi = bounds
    far = np.inf
    for k in range(3):
        if abs(direction[k]) > 1e-12:
            wall = hi[k] if direction[k] > 0 else lo[k]
            far = min(far, (wall - centre[k]) / direction[k])
    return far


def look_at(slot, distance: float | None = None, fov: float = 60.0, aspect: float = 1.0,
            bounds=None):
    """(eye, target) 3-tuples for a camera in front of `slot` (a PaintingSlot); `bounds`
    (room_bounds) limits the default distance."""
    if not (math.isfinite(fov) and 0 < fov < 180):
        raise ValueError(f"the field of view must be in (0, 180) degrees, got {fov}")
    given = distance is not None
    if distance is not None and not (math.isfinite(distance) and 0.05 <= distance <= 1000):
        raise ValueError(f"--distance must be in [0.05, 1000] metres, got {distance}")
    u, v = np.array(slot.u_axis, float), np.array(slot.v_axis, float)
    centre = np.array(slot.origin, float) + u * slot.width_m / 2 + v * slot.height_m / 2
    front = np.cross(v, u)  # u x v points into the wall: the visitor is on v x u's side
    front /= np.linalg.norm(front)
    if abs(front[1]) > 0.9:  # facing up or down: from the visitor's side (image bottom, +v)
        down = v / np.linalg.norm(v)
        front = (front + down) / np.linalg.norm(front + down)
    if distance is None:  # at least 5 cm: a tiny painting is seen from a camera's nearest
        corners = [np.array(slot.origin, float) + a * u * slot.width_m + b * v * slot.height_m
                   for a in (0, 1) for b in (0, 1)]
        distance = max(0.05, _fitting_distance(centre, front, corners, fov, aspect))
    if not given and bounds is not None:
        room = _inside_distance(centre, front, bounds) - 0.05
        if room > 0.05:
            distance = min(distance, room)
    eye = centre + distance * front
    return tuple(float(x) for x in eye), tuple(float(x) for x in centre)

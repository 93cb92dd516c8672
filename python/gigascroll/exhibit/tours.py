"""Tours: keyframes (position, target, time) and the camera path through them.

Between keyframes the head's position and its target each follow a centripetal Catmull-Rom
curve (alpha = 0.5: knot intervals |P_i+1 - P_i|^0.5, the parameterisation that Yuksel,
Schaefer and Keyser ("Parameterization and applications of Catmull-Rom curves", 2011) prove
free of cusps and self-intersections within a segment), evaluated with the Barry-Goldman
pyramid. Keyframe i's time maps linearly onto its segment's knot interval. The curve's ends
take mirrored neighbours (P_-1 = 2 P_0 - P_1); two keyframes at one place are a stop (the
segment stays there), and a neighbour that coincides with its segment's end is mirrored the
same way, so no knot interval is zero.

Limits: the head's speed along the curve (sampled densely) at most `max_speed_mps` (default
1.0 m/s, walking) and its height within [min_height_m, max_height_m] (default 1.2..2.0 m);
a violation is a ValueError naming the keyframe. The tour JSON format is tour.schema.json
(docs/cameras-and-tours.md); an exhibition file's [tour] table is the same object.

`default_tour` visits every painting: it stands at each painting's look-at point (cameras.py)
for STOP_S seconds and walks between them at WALK_MPS, in a floor plan room through the free
space (CLEARANCE_M from the walls and tables, around corners by the shortest route through
the free space's corners, looking along each leg until the last, which turns to the next
painting); in other rooms straight."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .schema import ExhibitionError, validate

__all__ = ["Tour", "tour_from_dict", "load_tour", "save_tour", "tour_to_dict", "catmull_rom",
           "tour_samples", "check_limits", "check_inside", "tour_path", "default_tour",
           "ALPHA"]

ALPHA = 0.5
STOP_S = 2.0
WALK_MPS = 0.6
CLEARANCE_M = 0.4
SAMPLES_PER_SEGMENT = 64
TOUR_FPS = 30.0


@dataclass
class Tour:
    position: np.ndarray   # (n, 3)
    target: np.ndarray     # (n, 3)
    time: np.ndarray       # (n,), strictly increasing
    max_speed_mps: float = 1.0
    min_height_m: float = 1.2
    max_height_m: float = 2.0
    fps: float = TOUR_FPS
    name: str = "tour"

    def __post_init__(self):
        self.position = np.asarray(self.position, np.float64).reshape(-1, 3)
        self.target = np.asarray(self.target, np.float64).reshape(-1, 3)
        self.time = np.asarray(self.time, np.float64).reshape(-1)
        n = len(self.time)
        if n < 2 or len(self.position) != n or len(self.target) != n:
            raise ValueError("a tour needs at least 2 keyframes, each with position, target and time")
        if not (np.all(np.isfinite(self.position)) and np.all(np.isfinite(self.target))
                and np.all(np.isfinite(self.time))):
            raise ValueError("tour keyframes must be finite")
        bad = np.flatnonzero(np.diff(self.time) <= 0)
        if bad.size:
            k = int(bad[0]) + 1
            raise ValueError(f"tour keyframe {k}: time {self.time[k]:g} s must be after keyframe "
                             f"{k - 1}'s {self.time[k - 1]:g} s")
        same = np.flatnonzero(np.all(self.position == self.target, axis=1))
        if same.size:
            raise ValueError(f"tour keyframe {int(same[0])}: target must differ from position")
        if not (self.min_height_m <= self.max_height_m):
            raise ValueError("tour min_height_m must be at most max_height_m")


def tour_from_dict(data, where: str) -> Tour:
    """A Tour from the tour object (schema-checked: ExhibitionError naming the key)."""
    validate(data, where, "tour")
    k = data["keyframes"]
    try:
        return Tour([x["position"] for x in k], [x["target"] for x in k],
                    [x["time"] for x in k], data.get("max_speed_mps", 1.0),
                    data.get("min_height_m", 1.2), data.get("max_height_m", 2.0),
                    data.get("fps", TOUR_FPS), data.get("name", "tour"))
    except ValueError as e:
        raise ExhibitionError(f"{where}: tour.keyframes: {e}") from None


def load_tour(path) -> Tour:
    """The tour in a JSON file (at most 16 MB)."""
    path = Path(path)
    try:
        if path.stat().st_size > 16 << 20:
            raise ExhibitionError(f"{path}: a tour file is at most 16 MB")
        data = json.loads(path.read_bytes().decode("utf-8"),
                          parse_constant=lambda c: (_ for _ in ()).throw(ValueError(f"{c} is not JSON")))
    except OSError as e:
        raise ExhibitionError(f"{path}: cannot read the tour file: {e.strerror or e}") from None
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise ExhibitionError(f"{path}: not a JSON tour file ({' '.join(str(e).split())[:200]})") from None
    return tour_from_dict(data, str(path))


def tour_to_dict(tour: Tour) -> dict:
    return {"name": tour.name, "fps": tour.fps, "max_speed_mps": tour.max_speed_mps,
            "min_height_m": tour.min_height_m, "max_height_m": tour.max_height_m,
            "keyframes": [{"position": p.tolist(), "target": t.tolist(), "time": float(s)}
                          for p, t, s in zip(tour.position, tour.target, tour.time)]}


def save_tour(tour: Tour, path) -> None:
    """Writes the tour as JSON atomically (outputs.write_text)."""
    from ..outputs import write_text
    write_text(path, json.dumps(tour_to_dict(tour), indent=1) + "\n")


# --- the curve -------------------------------------------------------------------------------

def _segment_points(points: np.ndarray, i: int):
    """P0..P3 around segment i (points i, i + 1), ends and coincident neighbours mirrored."""
    p1, p2 = points[i], points[i + 1]
    p0 = points[i - 1] if i > 0 else None
    p3 = points[i + 2] if i + 2 < len(points) else None
    if p0 is None or np.allclose(p0, p1, rtol=0, atol=1e-12):
        p0 = 2 * p1 - p2
    if p3 is None or np.allclose(p3, p2, rtol=0, atol=1e-12):
        p3 = 2 * p2 - p1
    return p0, p1, p2, p3


def _barry_goldman(p0, p1, p2, p3, s: np.ndarray, alpha: float) -> np.ndarray:
    """Points of the Catmull-Rom segment p1 -> p2 at fractions s in [0, 1] of its knot span."""
    def knot(a, b):
        return max(float(np.linalg.norm(b - a)) ** alpha, 1e-12)
    t0 = 0.0
    t1 = t0 + knot(p0, p1)
    t2 = t1 + knot(p1, p2)
    t3 = t2 + knot(p2, p3)
    t = (t1 + s * (t2 - t1))[:, None]

    def lerp(a, b, ta, tb):
        return (tb - t) / (tb - ta) * a + (t - ta) / (tb - ta) * b
    a1, a2, a3 = lerp(p0, p1, t0, t1), lerp(p1, p2, t1, t2), lerp(p2, p3, t2, t3)
    b1, b2 = lerp(a1, a2, t0, t2), lerp(a2, a3, t1, t3)
    return lerp(b1, b2, t1, t2)


def catmull_rom(points, times, at, alpha: float = ALPHA) -> np.ndarray:
    """The curve through `points` (n, d) at keyframe `times` (n,), evaluated at times `at`
    (clamped to the first and last keyframe)."""
    points = np.asarray(points, np.float64)
    times = np.asarray(times, np.float64)
    at = np.clip(np.asarray(at, np.float64).reshape(-1), times[0], times[-1])
    seg = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    out = np.empty((len(at), points.shape[1]))
    for i in np.unique(seg):
        m = seg == i
        s = (at[m] - times[i]) / (times[i + 1] - times[i])
        p0, p1, p2, p3 = _segment_points(points, int(i))
        if np.array_equal(p1, p2):
            out[m] = p1
        else:
            out[m] = _barry_goldman(p0, p1, p2, p3, s, alpha)
    return out


def tour_samples(tour: Tour, per_segment: int = SAMPLES_PER_SEGMENT):
    """(times, positions, segment of each sample): every segment sampled `per_segment` times."""
    ts = np.concatenate([np.linspace(a, b, per_segment, endpoint=False)
                         for a, b in zip(tour.time[:-1], tour.time[1:])] + [tour.time[-1:]])
    seg = np.clip(np.searchsorted(tour.time, ts, side="right") - 1, 0, len(tour.time) - 2)
    return ts, catmull_rom(tour.position, tour.time, ts), seg


def max_speed(tour: Tour) -> tuple[float, int]:
    """The highest sampled speed along the curve (m/s) and the keyframe its segment starts at."""
    ts, pos, seg = tour_samples(tour)
    speed = np.linalg.norm(np.diff(pos, axis=0), axis=1) / np.diff(ts)
    k = int(np.argmax(speed))
    return float(speed[k]), int(seg[k])


def check_limits(tour: Tour) -> None:
    """ValueError naming the keyframe where the head moves too fast or leaves the height band."""
    ts, pos, seg = tour_samples(tour)
    low = np.flatnonzero((pos[:, 1] < tour.min_height_m - 1e-9)
                         | (pos[:, 1] > tour.max_height_m + 1e-9))
    if low.size:
        j = int(low[0])
        k = int(seg[j])
        raise ValueError(f"tour keyframe {k} (t = {tour.time[k]:g} s): the head is at "
                         f"{pos[j, 1]:.3g} m between keyframes {k} and {k + 1}, outside "
                         f"{tour.min_height_m:g}..{tour.max_height_m:g} m (min_height_m, "
                         "max_height_m)")
    speed, k = max_speed(tour)
    if speed > tour.max_speed_mps * (1 + 1e-9):
        raise ValueError(f"tour keyframe {k} (t = {tour.time[k]:g} s): the head moves at "
                         f"{speed:.3g} m/s between keyframes {k} and {k + 1}, faster than "
                         f"max_speed_mps {tour.max_speed_mps:g}")


def check_inside(tour: Tour, ex) -> None:
    """ValueError naming the keyframe where the head (sampled as for check_limits) leaves a
    floor plan room's polygon (`ex` an Exhibition with walls): a tour that walks through
    walls is never silent. Other rooms are not checked: the built-in ones are open on the
    visitor's side."""
    if ex is None or "walls" not in ex.room:
        return
    import shapely

    from .floor_plan import floor_polygon
    ts, pos, seg = tour_samples(tour)
    x, z = pos[:, 0], pos[:, 2]
    bad = np.flatnonzero(~shapely.contains_xy(floor_polygon(ex), x, z))
    if bad.size:
        j = int(bad[0])
        k = int(seg[j])
        raise ValueError(f"tour keyframe {k} (t = {tour.time[k]:g} s): the head is at x = "
                         f"{x[j]:.3g}, z = {z[j]:.3g} m between keyframes {k} and "
                         f"{k + 1}, outside the floor plan")


def tour_path(tour: Tour, fps: float | None = None):
    """The tour as a CameraPath (views.CameraPath: per frame position, forward, up = +y),
    limits checked first."""
    from ..views import CameraPath
    check_limits(tour)
    fps = fps or tour.fps
    n = max(2, int(math.floor((tour.time[-1] - tour.time[0]) * fps)) + 1)
    ts = tour.time[0] + np.arange(n) / fps
    pos = catmull_rom(tour.position, tour.time, ts)
    tgt = catmull_rom(tour.target, tour.time, ts)
    fwd = tgt - pos
    tiny = np.linalg.norm(fwd, axis=1) < 1e-6
    if tiny.any():  # the target curve passed through the head: keep the last direction
        for k in np.flatnonzero(tiny):
            fwd[k] = fwd[k - 1] if k else tour.target[0] - tour.position[0]
    up = np.tile([0.0, 1.0, 0.0], (n, 1))
    vertical = np.abs(fwd[:, 1]) > 0.999 * np.linalg.norm(fwd, axis=1)
    up[vertical] = [0.0, 0.0, -1.0]
    return CameraPath(pos, fwd, up, None, None, fps, f"tour:{tour.name}")


# --- the default tour ------------------------------------------------------------------------

def default_tour(room, ex=None, fov: float = 60.0, aspect: float = 1.0,
                 max_speed_mps: float = 1.0) -> Tour:
    """A tour of every painting of `room` (a RoomSpec; labels, slots named label-*, are
    skipped); `ex`, the Exhibition of a floor plan room, gives the free space to walk in.
    The head turns in place (TURN_STEP_DEG at a time) before and after each walk, and looks
    2 m ahead along each leg while walking, so the target never passes through the head."""
    free = _free_space(ex) if ex is not None and "walls" in ex.room else None
    stops = _stops(room, free, fov, aspect)
    pos, tgt, times = [stops[0][0]], [stops[0][1]], [0.0]

    def add(p, t, dt):
        pos.append(np.asarray(p, float))
        tgt.append(np.asarray(t, float))
        times.append(times[-1] + dt)
    add(stops[0][0], stops[0][1], STOP_S)
    for (a, ta), (b, tb) in zip(stops, stops[1:]):
        route = _route(free, a, b)
        _turn(add, a, ta, a + 2.0 * _unit(route[1] - a))
        for k, (p, q) in enumerate(zip(route, route[1:])):
            ahead = q + 2.0 * _unit((route[k + 2] if k + 2 < len(route) else q + (q - p)) - q)
            add(q, ahead, max(0.2, float(np.linalg.norm(q - p)) / WALK_MPS))
        _turn(add, b, tgt[-1], tb)
        add(b, tb, STOP_S)
    tour = Tour(pos, tgt, times, max_speed_mps=max_speed_mps, name="default")
    speed, _ = max_speed(tour)
    if speed > 0.95 * max_speed_mps:  # slow down uniformly until the curve keeps the limit
        tour.time = tour.time * (speed / (0.95 * max_speed_mps))
    return tour


def _stops(room, free, fov: float, aspect: float) -> list:
    """(eye, painting centre) of each painting: its look-at point, at least CLEARANCE_M +
    0.2 m from its wall in a floor plan, the head between 1.3 and 1.9 m."""
    from .cameras import look_at, room_bounds
    bounds = room_bounds(room)
    stops = []
    for slot in room.paintings:
        if str(slot.name).startswith("label-"):
            continue
        eye, centre = look_at(slot, None, fov, aspect, bounds)
        eye = np.array(eye)
        flat = (eye - np.array(centre)) * [1.0, 0.0, 1.0]
        reach = float(np.linalg.norm(flat))
        if free is not None and 1e-9 < reach < CLEARANCE_M + 0.2:
            eye = eye + flat / reach * (CLEARANCE_M + 0.2 - reach)
        eye[1] = min(1.9, max(1.3, eye[1]))
        stops.append((eye, np.array(centre)))
    if not stops:
        raise ValueError(f"room {room.name!r} has no paintings to tour")
    return stops


TURN_STEP_DEG = 45.0
TURN_STEP_S = 0.5


def _turn(add, at: np.ndarray, start: np.ndarray, end: np.ndarray) -> None:
    """Keyframes turning the head at `at` from looking at `start` to looking at `end` about
    the vertical, through targets 2 m away every TURN_STEP_DEG (the last one `end`)."""
    def yaw(p):
        d = np.asarray(p, float) - at
        return math.atan2(d[0], d[2]) if math.hypot(d[0], d[2]) > 1e-9 else None
    y0, y1 = yaw(start), yaw(end)
    if y0 is None or y1 is None:
        add(at, end, TURN_STEP_S)
        return
    delta = (y1 - y0 + math.pi) % (2 * math.pi) - math.pi
    steps = max(1, math.ceil(abs(math.degrees(delta)) / TURN_STEP_DEG))
    for k in range(1, steps):
        a = y0 + delta * k / steps
        add(at, at + 2.0 * np.array([math.sin(a), 0.0, math.cos(a)]), TURN_STEP_S)
    add(at, end, TURN_STEP_S)


def _unit(d: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(d))
    return d / n if n > 1e-9 else np.array([0.0, 0.0, -1.0])


def _free_space(ex):
    """Where a visitor's head may go: the floor plan shrunk by CLEARANCE_M, minus the tables'
    footprints grown by it."""
    from .floor_plan import floor_polygon, table_axes
    from shapely.geometry import Polygon
    free = floor_polygon(ex).buffer(-CLEARANCE_M, join_style="mitre")
    for p in ex.paintings:
        h = p.hang
        if h is not None and h.on is not None:
            u, _, back = table_axes(h)
            hw = p.width_m / 2 + 0.05
            hd = p.height_m * math.cos(math.radians(h.tilt_deg)) / 2 + 0.05
            c = np.array(h.position_m)
            ux, bx = np.array([u[0], u[2]]), np.array([back[0], back[2]])
            foot = Polygon([c + sx * hw * ux + sz * hd * bx
                            for sx, sz in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
            free = free.difference(foot.buffer(CLEARANCE_M, join_style="mitre"))
    return free


def _route(free, a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Points from a to b (3-D, at a's and b's heights): straight where the free space allows
    it, else the shortest path through the free space's corners (a visibility graph)."""
    if free is None or free.is_empty:
        return [a, b]
    from shapely.geometry import LineString, Point
    from shapely.ops import nearest_points
    inside = free.buffer(1e-6)

    def entry(p):  # a stop outside the free space walks to its nearest point first
        q = Point(p[0], p[2])
        return q if inside.contains(q) else nearest_points(free, q)[0]
    pa, pb = entry(a), entry(b)
    nodes = [(pa.x, pa.y), (pb.x, pb.y)]
    for geom in getattr(free, "geoms", [free]):
        shrunk = geom.buffer(-1e-3, join_style="mitre")
        for g in getattr(shrunk, "geoms", [shrunk]):
            nodes += list(g.exterior.coords)[:-1]
            for ring in g.interiors:
                nodes += list(ring.coords)[:-1]
    n = len(nodes)
    dist = [math.inf] * n
    prev = [-1] * n
    dist[0], done = 0.0, [False] * n
    for _ in range(n):  # Dijkstra over the visibility graph
        i = min((k for k in range(n) if not done[k]), key=lambda k: dist[k], default=None)
        if i is None or dist[i] == math.inf:
            break
        done[i] = True
        if i == 1:
            break
        for j in range(n):
            if not done[j] and dist[i] + math.dist(nodes[i], nodes[j]) < dist[j] \
                    and inside.contains(LineString([nodes[i], nodes[j]])):
                dist[j], prev[j] = dist[i] + math.dist(nodes[i], nodes[j]), i
    if prev[1] < 0 and nodes[0] != nodes[1]:
        return [a, b]  # no route in the free space (separate parts): straight
    chain, k = [], 1
    while k >= 0:
        chain.append(nodes[k])
        k = prev[k]
    chain.reverse()
    heights = np.linspace(a[1], b[1], len(chain))
    pts = [a] + [np.array([x, y_, z]) for (x, z), y_ in zip(chain, heights)] + [b]
    out = [pts[0]]
    for p in pts[1:]:
        if np.linalg.norm(p - out[-1]) > 1e-6:
            out.append(p)
    return out if len(out) >= 2 else [a, b]

"""Camera paths: per-frame head poses and magnifier targets, shared as data by scenarios,
benchmarks and tests (saved and loaded as JSON), and the views each frame renders."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._core import Camera
from ..outputs import write_text
from .exhibition import (FPS, HEADSET, MAGNIFIER, SCROLL, TABLE4_PAINTINGS, Exhibition, Headset,
                         Magnifier, PaintingSpec)

__all__ = ["CameraPath", "scroll_path", "multi_route", "frame_cameras"]


# The core's bound on coordinates (cpp/common/limits.h: kMaxCoordinate), checked here so that a
# path is refused when it is made, not at the frame that reaches the bad pose.
MAX_COORDINATE = 1e12
# A frame rate beyond any display's (and beyond what an MP4's time base can hold).
MAX_FPS = 1000.0


def _finite(name: str, a: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(a)):
        raise ValueError(f"camera path {name} contains NaN or infinite values")
    return a


def _unit_rows(a: np.ndarray) -> np.ndarray:
    """Rows of `a` scaled to unit length without overflow or underflow (each row divided by
    its largest component first); rows of zeros or subnormals (no direction the core can
    normalise) become zero."""
    scale = np.max(np.abs(a), axis=1, keepdims=True)
    b = np.divide(a, scale, out=np.zeros_like(a), where=scale >= np.finfo(np.float64).tiny)
    norm = np.linalg.norm(b, axis=1, keepdims=True)
    return np.divide(b, norm, out=np.zeros_like(b), where=norm > 0)


def _first_bad(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask)[0])


@dataclass
class CameraPath:
    """Per-frame head pose (position, forward, up; the eyes sit +-ipd/2 along right) and the
    magnifier's target on the painting (NaN rows: no magnifier that frame). Shared data:
    scenarios, benchmarks and tests replay the same paths; save()/load() keep them as JSON."""
    position: np.ndarray   # (n, 3)
    forward: np.ndarray    # (n, 3)
    up: np.ndarray         # (n, 3)
    magnifier_target: np.ndarray | None = None  # (n, 3) point on the painting
    magnifier_normal: np.ndarray | None = None  # (n, 3) painting normal, towards the viewer
    fps: float = FPS
    name: str = ""

    def __post_init__(self):
        for attr in ("position", "forward", "up"):
            a = np.ascontiguousarray(getattr(self, attr), dtype=np.float64)
            if a.ndim != 2 or a.shape[1] != 3 or len(a) == 0:
                raise ValueError(f"camera path {attr} must have shape (n, 3), n > 0")
            setattr(self, attr, _finite(attr, a))
        n = len(self.position)
        if len(self.forward) != n or len(self.up) != n:
            raise ValueError("camera path arrays differ in length")
        far = np.max(np.abs(self.position), axis=1) > MAX_COORDINATE
        if np.any(far):
            raise ValueError(f"camera path position of frame {_first_bad(far)} is beyond "
                             f"+-{MAX_COORDINATE:g}")
        f, u = _unit_rows(self.forward), _unit_rows(self.up)
        if np.any(~f.any(axis=1)):
            raise ValueError("camera path has a zero forward vector")
        if np.any(~u.any(axis=1)):
            raise ValueError("camera path has a zero up vector")
        parallel = np.linalg.norm(np.cross(f, u), axis=1) < 1e-6
        if np.any(parallel):
            raise ValueError(f"camera path forward and up are parallel at frame {_first_bad(parallel)}")
        if (self.magnifier_target is None) != (self.magnifier_normal is None):
            raise ValueError("camera path has magnifier_target without magnifier_normal (or the "
                             "reverse): give both or neither")
        for attr in ("magnifier_target", "magnifier_normal"):
            a = getattr(self, attr)
            if a is not None:
                a = np.asarray(a, dtype=np.float64)
                if a.shape != (n, 3):
                    raise ValueError(f"camera path {attr} must have shape ({n}, 3), got {a.shape}")
                if np.any(np.isinf(a)):
                    raise ValueError(f"camera path {attr} contains infinite values")
                setattr(self, attr, a)
        if self.magnifier_target is not None:
            # A frame has a magnifier when its target is finite; its normal must then be too.
            on = np.all(np.isfinite(self.magnifier_target), axis=1)
            far = on & (np.max(np.abs(np.nan_to_num(self.magnifier_target)), axis=1) > MAX_COORDINATE)
            if np.any(far):
                raise ValueError(f"camera path magnifier_target of frame {_first_bad(far)} is beyond "
                                 f"+-{MAX_COORDINATE:g}")
            normal = np.nan_to_num(self.magnifier_normal, nan=0.0)
            bad = on & ~(np.all(np.isfinite(self.magnifier_normal), axis=1) & _unit_rows(normal).any(axis=1))
            if np.any(bad):
                raise ValueError(f"camera path magnifier_normal of frame {_first_bad(bad)} must be "
                                 "finite and non-zero where magnifier_target is given")
        if not (math.isfinite(self.fps) and 0 < self.fps <= MAX_FPS):
            raise ValueError(f"camera path fps must be positive and at most {MAX_FPS:g}")

    def __len__(self) -> int:
        return len(self.position)

    def then(self, other: "CameraPath") -> "CameraPath":
        """This path followed by another."""
        def cat(a, b, n_a, n_b):
            if a is None and b is None:
                return None
            a = np.full((n_a, 3), np.nan) if a is None else a
            b = np.full((n_b, 3), np.nan) if b is None else b
            return np.concatenate([a, b])
        n, m = len(self), len(other)
        return CameraPath(np.concatenate([self.position, other.position]),
                          np.concatenate([self.forward, other.forward]),
                          np.concatenate([self.up, other.up]),
                          cat(self.magnifier_target, other.magnifier_target, n, m),
                          cat(self.magnifier_normal, other.magnifier_normal, n, m),
                          self.fps, self.name)

    def hold(self, frames: int) -> "CameraPath":
        """This path, then `frames` frames standing still at its last pose (the "stop")."""
        if frames < 0:
            raise ValueError("hold frames must be >= 0")
        if frames == 0:
            return self
        rep = lambda a: None if a is None else np.repeat(a[-1:], frames, axis=0)  # noqa: E731
        return self.then(CameraPath(rep(self.position), rep(self.forward), rep(self.up),
                                    rep(self.magnifier_target), rep(self.magnifier_normal),
                                    self.fps))

    def save(self, path: str | Path) -> None:
        def enc(a):
            return None if a is None else np.where(np.isnan(a), None, a).tolist()
        write_text(path, json.dumps({
            "name": self.name, "fps": self.fps, "position": self.position.tolist(),
            "forward": self.forward.tolist(), "up": self.up.tolist(),
            "magnifier_target": enc(self.magnifier_target),
            "magnifier_normal": enc(self.magnifier_normal)}))

    @classmethod
    def load(cls, path: str | Path) -> "CameraPath":
        try:
            d = json.loads(Path(path).read_text())
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise ValueError(f"{path}: not a camera path JSON file ({e})") from None
        except RecursionError:
            raise ValueError(f"{path}: not a camera path JSON file (nested too deeply)") from None
        if not isinstance(d, dict):
            raise ValueError(f"{path}: not a camera path JSON file (expected an object)")

        def dec(name, nulls=False):
            a = d[name] if not nulls else d.get(name)
            if a is None and nulls:
                return None
            _only_numbers(path, name, a, nulls)
            return np.array([[np.nan if v is None else v for v in row] for row in a]
                            if nulls else a, dtype=np.float64)
        try:
            return cls(dec("position"), dec("forward"), dec("up"),
                       dec("magnifier_target", True), dec("magnifier_normal", True),
                       _number(path, d.get("fps", FPS)), d.get("name", ""))
        except KeyError as e:
            raise ValueError(f"{path}: camera path file is missing {e}") from None
        except (TypeError, OverflowError, RecursionError) as e:
            msg = "nested too deeply" if isinstance(e, RecursionError) else e
            raise ValueError(f"{path}: camera path file has values of the wrong type ({msg})") from None


def _only_numbers(path, name: str, rows, nulls: bool) -> None:
    """ValueError unless `rows` is a list of lists of JSON numbers (and nulls where allowed):
    numpy would read "6" as 6.0 and true as 1.0, a wrong path rather than an error."""
    if not isinstance(rows, list) or not all(isinstance(r, list) for r in rows):
        raise ValueError(f"{path}: camera path file has values of the wrong type ({name} must "
                         "be a list of [x, y, z] rows)")
    for k, row in enumerate(rows):
        if len(row) != 3:
            raise ValueError(f"{path}: camera path {name} must have shape (n, 3), row {k} has "
                             f"{len(row)} values")
        for v in row:
            if not (v is None and nulls) and (isinstance(v, bool) or not isinstance(v, (int, float))):
                raise ValueError(f"{path}: camera path file has values of the wrong type "
                                 f"({name} row {k} holds {v!r:.40}, not a number)")


def _number(path, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{path}: camera path fps must be a number, got {v!r}"[:200])
    return float(v)


def scroll_path(distance: float = 0.40, speed: float = 1.0, duration: float = 10.0,
                start_x: float = 1.0, stop_frames: int = 0, loops: int = 1,
                magnifier: bool = True, exhibition: Exhibition | None = None,
                centre_height: float = 1.5, fps: float = FPS) -> CameraPath:
    """VT-mobile-VR's single-painting behaviour: facing the wall scroll from `distance`, move
    left to right at constant `speed` for `duration` seconds, `loops` times (jumping back to
    the start, as in Table 1), then stand still for `stop_frames`. The magnifier looks at the
    point straight ahead of the head."""
    for name, v in (("distance", distance), ("speed", speed), ("duration", duration),
                    ("start_x", start_x), ("centre_height", centre_height)):
        if not math.isfinite(v):
            raise ValueError(f"scroll_path {name} must be finite")
    if distance <= 0 or speed < 0 or duration <= 0 or loops < 1:
        raise ValueError("scroll_path needs distance > 0, speed >= 0, duration > 0, loops >= 1")
    width = exhibition.specs[0].width_m if exhibition else SCROLL.width_m
    n = max(1, int(round(duration * fps)))
    x = start_x + speed * np.arange(n) / fps
    if x[-1] > width:
        raise ValueError(f"scroll_path runs off the {width} m painting (ends at x = {x[-1]:.2f})")
    x = np.tile(x, loops)
    n = len(x)
    pos = np.stack([x, np.full(n, centre_height), np.full(n, -distance)], axis=1)
    fwd = np.tile([0.0, 0.0, 1.0], (n, 1))
    up = np.tile([0.0, 1.0, 0.0], (n, 1))
    target = normal = None
    if magnifier:
        target = np.stack([x, np.full(n, centre_height), np.zeros(n)], axis=1)
        normal = np.tile([0.0, 0.0, -1.0], (n, 1))
    return CameraPath(pos, fwd, up, target, normal, fps, "scroll").hold(stop_frames)


def multi_route(n_paintings: int, speed: float = 1.0, duration: float = 10.0,
                eye_height: float = 1.70, tilt_deg: float | None = None,
                fps: float = FPS, specs: list[PaintingSpec] | None = None) -> CameraPath:
    """VT-mobile-VR §5.4's routes: the camera 170 cm above the floor walks along the
    tables' near edge (+x) at `speed`, tilted down so the tables in front are in view; more
    paintings = more tables behind, so the tilt flattens to take in the farther ones."""
    specs = specs or TABLE4_PAINTINGS
    if n_paintings < 1 or n_paintings % len(specs):
        raise ValueError(f"n_paintings must be a positive multiple of {len(specs)}")
    if not (speed >= 0 and duration > 0 and math.isfinite(speed) and math.isfinite(duration)):
        raise ValueError("multi_route needs finite speed >= 0 and duration > 0")
    gap = 0.10
    depth = sum(s.height_m for s in specs) + (len(specs) + 1) * gap
    groups = n_paintings // len(specs)
    far = 1.0 + groups * (depth + 1.0) - 1.0  # far edge of the last table
    if tilt_deg is None:
        # Aim at the middle of the occupied tables' depth.
        mid = (1.0 + far) / 2
        tilt_deg = math.degrees(math.atan2(eye_height - 0.70, mid + 0.5))
    t = math.radians(tilt_deg)
    n = max(1, int(round(duration * fps)))
    x = 2.0 + speed * np.arange(n) / fps
    pos = np.stack([x, np.full(n, eye_height), np.full(n, -0.5)], axis=1)
    fwd = np.tile([0.0, -math.sin(t), math.cos(t)], (n, 1))
    up = np.tile([0.0, math.cos(t), math.sin(t)], (n, 1))
    return CameraPath(pos, fwd, up, None, None, fps, f"multi{n_paintings}")


def frame_cameras(path: CameraPath, frame: int, headset: Headset = HEADSET,
                  magnifier: Magnifier | None = MAGNIFIER) -> list[tuple[Camera, int, int]]:
    """The views of one frame as (camera, feedback width, feedback height): left eye, right
    eye (parallel, +-ipd/2 along the head's right vector), and the magnifier when the path
    has a target that frame."""
    if not 0 <= frame < len(path):
        raise ValueError(f"frame {frame} outside the camera path's {len(path)} frames")
    p, f, u = path.position[frame], path.forward[frame], path.up[frame]
    with np.errstate(all="ignore"):
        right = np.cross(f, u)
        length = np.linalg.norm(right)
    if not (np.isfinite(length) and length > 0):  # vectors so long or short that it overflowed
        right = np.cross(_unit_rows(f[None])[0], _unit_rows(u[None])[0])
        length = np.linalg.norm(right)
    right = right / length
    fw, fh = headset.width // headset.feedback_scale, headset.height // headset.feedback_scale
    views = []
    for side in (-1, 1):
        eye = p + side * headset.ipd / 2 * right
        views.append((Camera(tuple(eye), tuple(f), tuple(u), headset.tan_half_x,
                             headset.tan_half_y, headset.width, headset.height), fw, fh))
    if magnifier is not None and path.magnifier_target is not None \
            and np.all(np.isfinite(path.magnifier_target[frame])):
        target, normal = path.magnifier_target[frame], path.magnifier_normal[frame]
        with np.errstate(all="ignore"):
            length = np.linalg.norm(normal)
        normal = normal / length if np.isfinite(length) and length > 0 else _unit_rows(normal[None])[0]
        cam_pos = target + magnifier.lens_distance * normal
        up_hint = u if abs(np.dot(u, normal)) < 0.99 else right
        tan_half = magnifier.field / 2 / magnifier.lens_distance
        r = magnifier.resolution
        views.append((Camera(tuple(cam_pos), tuple(-normal), tuple(up_hint), tan_half, tan_half,
                             r, r), r, r))
    return views

"""scene.json: what the browser client needs to draw the room (docs/serve-protocol.md)."""

from __future__ import annotations

from ..errors import expect_type
from ..display_mapping import Display
from ..gallery.exposure import room_display
from .pack_info import pack_description

__all__ = ["MAX_BATCH", "scene_document"]

MAX_BATCH = 64          # tiles per batch request
DEFAULT_FOV = 60.0      # degrees, vertical: `render --room`'s suggested view


def _floats(v) -> list[float]:
    return [float(x) for x in v]


def scene_document(pack, content_hash: str, room, display: Display | None = None) -> dict:
    """The scene of a served pack and BakedRoom; `display`: the camera response the client
    applies (display_mapping; None: the room's automatic exposure and the neutral curve)."""
    from .room_bake import BakedRoom

    expect_type(room, BakedRoom, "room")
    if display is None:
        display = room_display(room.spec)
    expect_type(display, Display, "display")
    spec, gallery = room.spec, room.gallery
    camera = gallery.camera()
    slots = [{"slot": k, "painting": gallery.slot_paintings[k], "origin": _floats(s.origin),
              "u_axis": _floats(s.u_axis), "v_axis": _floats(s.v_axis),
              "width_m": float(s.width_m), "height_m": float(s.height_m)}
             for k, s in enumerate(spec.paintings)]
    lo, hi = gallery.bounds
    h = content_hash
    return {
        "version": 1,
        "pack": pack_description(pack, content_hash),
        "room": {"name": spec.name, "glb": f"/api/room/{room.key}.glb",
                 "bounds": [_floats(lo), _floats(hi)],
                 "camera": {"eye": _floats(camera.position),
                            "target": _floats(_target(spec, camera)), "fov": DEFAULT_FOV},
                 "slots": slots},
        "display": display.scene_json(),
        "tiles": {"tile": f"/api/tiles/{h}/{{painting}}/{{level}}/{{tx}}/{{ty}}",
                  "batch": f"/api/tiles/{h}/batch", "max_batch": MAX_BATCH},
    }


def _target(spec, camera):
    """The room's suggested target, else a point 1 m along the default camera's view."""
    if spec.camera_target is not None and spec.camera_eye is not None:
        return spec.camera_target
    return [p + f for p, f in zip(camera.position, camera.forward)]

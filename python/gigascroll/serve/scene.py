"""scene.json: what the browser client needs to draw the room (docs/serve-protocol.md)."""

from __future__ import annotations

from ..errors import expect_type
from ..gallery.walk import lit_exposure
from .pack_info import pack_description

__all__ = ["MAX_BATCH", "TONE", "scene_document"]

MAX_BATCH = 64          # tiles per batch request
TONE = "clip-srgb"      # walk.tone_map: sRGB(clamp(exposure * radiance, 0, 1))
DEFAULT_FOV = 60.0      # degrees, vertical: `render --room`'s suggested view


def _floats(v) -> list[float]:
    return [float(x) for x in v]


def scene_document(pack, content_hash: str, room) -> dict:
    """The scene of a served pack and BakedRoom."""
    from .room_bake import BakedRoom

    expect_type(room, BakedRoom, "room")
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
        "display": {"exposure": lit_exposure(), "tone": TONE},
        "tiles": {"tile": f"/api/tiles/{h}/{{painting}}/{{level}}/{{tx}}/{{ty}}",
                  "batch": f"/api/tiles/{h}/batch", "max_batch": MAX_BATCH},
    }


def _target(spec, camera):
    """The room's suggested target, else a point 1 m along the default camera's view."""
    if spec.camera_target is not None and spec.camera_eye is not None:
        return spec.camera_target
    return [p + f for p, f in zip(camera.position, camera.forward)]

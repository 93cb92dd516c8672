"""The lit gallery: one room in which the paintings of a pack are lit by the photon map (the
bake, the illuminance and exposure figures, the light solve and report).

The room it lights is a `gigascroll.room.RoomSpec`; the room model's names are re-exported
here, as they were before the room had a package of its own."""

from ..room.builtin import ROOM_NAMES, builtin_room
from ..room.spec import PaintingSlot, RoomSpec, Surface
from .gallery import LIGHTING_MODES, PAINTING_REFLECTANCE, Gallery, painting_albedo

__all__ = ["Gallery", "LIGHTING_MODES", "PAINTING_REFLECTANCE", "PaintingSlot", "RoomSpec", "Surface",
           "painting_albedo", "ROOM_NAMES", "builtin_room"]

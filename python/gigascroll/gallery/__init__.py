"""The gallery: one room in which the paintings of a pack are lit by the photon map."""

from .gallery import LIGHTING_MODES, PAINTING_REFLECTANCE, Gallery, painting_albedo
from ..room.spec import PaintingSlot, RoomSpec, Surface
from ..room.builtin import ROOM_NAMES, builtin_room

__all__ = ["Gallery", "LIGHTING_MODES", "PAINTING_REFLECTANCE", "PaintingSlot", "RoomSpec", "Surface",
           "painting_albedo", "ROOM_NAMES", "builtin_room"]

"""The gallery: one room in which the paintings of a pack are lit by the photon map."""

from .room import PaintingSlot, RoomSpec, Surface
from .rooms import ROOM_NAMES, builtin_room

__all__ = ["PaintingSlot", "RoomSpec", "Surface", "ROOM_NAMES", "builtin_room"]

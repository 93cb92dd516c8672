"""The gallery: one room in which the paintings of a pack are lit by the photon map."""

from .room import PaintingSlot, RoomSpec, Surface
from .room_files import load_room, save_room
from .rooms import ROOM_NAMES, builtin_room

__all__ = ["PaintingSlot", "RoomSpec", "Surface", "ROOM_NAMES", "builtin_room", "load_room",
           "save_room"]

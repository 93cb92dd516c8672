"""The gallery: one room in which the paintings of a pack are lit by the photon map."""

from .room import PaintingSlot, RoomSpec, Surface

__all__ = ["PaintingSlot", "RoomSpec", "Surface"]

"""The gallery: one room in which the paintings of a pack are lit by the photon map."""

from .gallery import LIGHTING_MODES, PAINTING_REFLECTANCE, Gallery, painting_albedo
from .room import PaintingSlot, RoomSpec, Surface

__all__ = ["Gallery", "LIGHTING_MODES", "PAINTING_REFLECTANCE", "PaintingSlot", "RoomSpec", "Surface",
           "painting_albedo"]

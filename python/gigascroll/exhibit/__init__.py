"""Exhibitions: a TOML file naming paintings (with metadata and physical sizes), the room,
where each painting hangs, frames, labels, lights and a tour (model.py, schema.py); the room
built from it (floor_plan.py); `exhibit build`'s show directory (build.py, show.py); cameras
at a painting and tours (cameras.py, tours.py)."""

from .model import Exhibition, Painting, load_exhibition
from .schema import ExhibitionError

__all__ = ["Exhibition", "Painting", "ExhibitionError", "load_exhibition"]

"""The room model: what a gallery room is made of before it is lit, as a `RoomSpec`.

Built-in rooms (`builtin`), room files (glTF, OBJ, PLY: `files`, which reads them and writes
them back), the lights as a lighting designer gives them (`lights`, `light_colour`), the
paintings' physical sizes (`sizes`) and the geometry that both the room and its lights need
(`polygon`: Lambert's formula; `slot_grid`: points over a painting). Nothing here bakes or
draws: `gigascroll.gallery` lights a `RoomSpec`, `gigascroll.walk` walks through it.
"""

from .builtin import ROOM_NAMES, builtin_room
from .spec import PaintingSlot, RoomSpec, Surface

__all__ = ["PaintingSlot", "RoomSpec", "Surface", "ROOM_NAMES", "builtin_room"]

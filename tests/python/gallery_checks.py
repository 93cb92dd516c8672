"""A small box room as a RoomSpec and packs of uniform or patterned paintings, shared by the
gallery tests."""

import numpy as np

from gigascroll import build_pack
from gigascroll.gallery import PaintingSlot, RoomSpec, Surface


def quad(c, a, b):
    """The rectangle c +- a +- b as 4 vertices and 2 triangles, facing a x b."""
    c, a, b = (np.array(x, float) for x in (c, a, b))
    return np.array([c - a - b, c + a - b, c + a + b, c - a + b]), np.array([[0, 1, 2], [0, 2, 3]])


def box_room(scale: float = 1.0, light: float = 5.0, floor=(0.8, 0.8, 0.8), wall=(0.6, 0.6, 0.6),
             gap: float = 0.001, painting="red", painting_albedo_walls=None, closed_light=False) -> RoomSpec:
    """A 4 m x 3 m x 4 m room (x, z in [-2, 2], y in [0, 3]) with inward-facing surfaces, a
    1 m square ceiling light facing down and a 2 m x 1 m painting `gap` metres in front of the
    back wall. Every length times `scale`."""
    s = float(scale)
    surfaces = []

    def add(name, c, a, b, albedo, emission=(0, 0, 0)):
        v, t = quad(np.array(c) * s, np.array(a) * s, np.array(b) * s)
        surfaces.append(Surface(name, v, t, tuple(albedo), tuple(emission)))

    add("floor", (0, 0, 0), (0, 0, 2), (2, 0, 0), floor)
    add("ceiling", (0, 3, 0), (2, 0, 0), (0, 0, 2), wall)
    add("back", (0, 1.5, -2), (2, 0, 0), (0, 1.5, 0), wall)
    add("front", (0, 1.5, 2), (0, 1.5, 0), (2, 0, 0), wall)
    add("left", (-2, 1.5, 0), (0, 1.5, 0), (0, 0, 2), wall)
    add("right", (2, 1.5, 0), (0, 0, 2), (0, 1.5, 0), wall)
    add("light", (0, 2.999, 0), (0.5, 0, 0), (0, 0, 0.5), (0, 0, 0), (light,) * 3)
    slots = [PaintingSlot(painting, origin=(-1.0 * s, 2.0 * s, (-2 + gap) * s), u_axis=(1, 0, 0),
                          v_axis=(0, -1, 0), width_m=2.0 * s, height_m=1.0 * s, name="main")]
    return RoomSpec("box", surfaces, slots, camera_eye=(0, 1.5 * s, 1.8 * s),
                    camera_target=(0, 1.2 * s, -2 * s))


def uniform_pack(path, colours: dict, size=(256, 128), tile_size=32, border=2):
    """A pack of uniform paintings {name: sRGB8 colour}."""
    w, h = size
    images = [np.broadcast_to(np.array(c, np.uint8), (h, w, 3)).copy() for c in colours.values()]
    return build_pack(images, path, tile_size=tile_size, border=border, names=list(colours))


def gradient_pack(path, size=(256, 128), tile_size=32, border=2):
    """One painting 'gradient': red rising along x, blue along y (smooth, so every mip level
    and filter agree to first order)."""
    w, h = size
    x = (np.arange(w) + 0.5) / w
    y = (np.arange(h) + 0.5) / h
    img = np.zeros((h, w, 3), np.uint8)
    img[..., 0] = (40 + 200 * x)[None, :]
    img[..., 1] = 60
    img[..., 2] = (40 + 200 * y)[:, None]
    return build_pack([img], path, tile_size=tile_size, border=border, names=["gradient"])


def example_room_files(d):
    """The example glTF room (d / "room.glb") and a pack of its two paintings in flat colours at a
    tenth of their size (d / "ex.pack"). Returns d."""
    from gigascroll import TilePack
    from gigascroll.room.example import EXAMPLE_PAINTINGS, write_example_room

    images = [np.full((h // 10, w // 10, 3), c, np.uint8)
              for (w, h), c in zip(EXAMPLE_PAINTINGS.values(), [(200, 60, 40), (40, 80, 200)])]
    build_pack(images, d / "ex.pack", tile_size=32, border=2, names=list(EXAMPLE_PAINTINGS))
    write_example_room(d / "room.glb", TilePack(d / "ex.pack"))
    return d

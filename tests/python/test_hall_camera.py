"""The hall's suggested camera sees its paintings upright and unmirrored.

A painting of four coloured quadrants lies on the hall's table; the suggested view is rendered
unlit. The reference is the source image itself: each quadrant's colour must show in the
matching quadrant of the painting's picture on screen (its top-left texels at the screen's
upper left), and the hits' uv must grow rightward (u) and downward (v) on screen, as the image's
x and y do.
"""

import numpy as np
import pytest

import gigascroll
from gigascroll.gallery import builtin_room
from gigascroll.room.sizes import PaintingSize

# Quadrant colours: top-left, top-right, bottom-left, bottom-right (sRGB 8-bit).
QUADRANTS = {"tl": (255, 0, 0), "tr": (0, 255, 0), "bl": (0, 0, 255), "br": (255, 255, 0)}


def quadrant_image(width=256, height=256) -> np.ndarray:
    img = np.empty((height, width, 3), np.uint8)
    h, w = height // 2, width // 2
    img[:h, :w], img[:h, w:] = QUADRANTS["tl"], QUADRANTS["tr"]
    img[h:, :w], img[h:, w:] = QUADRANTS["bl"], QUADRANTS["br"]
    return img


@pytest.fixture(scope="module")
def hall_view(tmp_path_factory):
    pack = gigascroll.build_pack([quadrant_image()], tmp_path_factory.mktemp("hall") / "q.pack")
    # 1 m x 1 m on the table, seen at a grazing 16 degrees from 3.6 m: a narrow field of
    # view makes its picture large enough for quadrants of a few hundred pixels each.
    spec = builtin_room("hall", [PaintingSize("q", 256, 256, 1.0, 1.0)])
    gallery = gigascroll.Gallery.from_room(spec, pack)
    camera = gallery.camera((200, 160), fov=25.0)
    vt = gigascroll.VirtualTexture(pack, (16, 16))
    gallery.stream(camera, vt)
    rgb, hits = gallery.render_display(camera, vt, "unlit", hits=True)
    return rgb, hits


def _dominant(rgb: np.ndarray) -> tuple[int, int, int]:
    """The quadrant colour nearest to the mean of these pixels (unlit: albedo, linear)."""
    mean = rgb.reshape(-1, 3).mean(axis=0)
    mean = mean / max(mean.max(), 1e-9)
    best = min(QUADRANTS.values(), key=lambda c: np.abs(np.array(c) / 255.0 - mean).sum())
    return best


def test_hall_camera_reads_the_painting_upright(hall_view):
    rgb, hits = hall_view
    on = hits["slot"] == 0
    assert on.sum() > 500, "the suggested view should show the painting"
    rows, cols = np.nonzero(on)
    r0, r1, c0, c1 = rows.min(), rows.max(), cols.min(), cols.max()
    rm, cm = (r0 + r1) // 2, (c0 + c1) // 2
    # Inner quarters of each screen quadrant of the painting's bounding box, away from seams.
    boxes = {"tl": (r0, rm, c0, cm), "tr": (r0, rm, cm, c1), "bl": (rm, r1, c0, cm),
             "br": (rm, r1, cm, c1)}
    for name, (a, b, c, d) in boxes.items():
        ra, rb = a + (b - a) // 4, b - (b - a) // 4
        ca, cb = c + (d - c) // 4, d - (d - c) // 4
        sel = on[ra:rb, ca:cb]
        assert sel.sum() > 10, name
        assert _dominant(rgb[ra:rb, ca:cb][sel]) == QUADRANTS[name], name


def test_hall_camera_uv_follows_the_screen(hall_view):
    _, hits = hall_view
    on = hits["slot"] == 0
    rows, cols = np.nonzero(on)
    u, v = hits["uv"][on, 0], hits["uv"][on, 1]
    # Least-squares gradients of u and v over the screen (columns right, rows down).
    design = np.column_stack([cols, rows, np.ones_like(cols)]).astype(float)
    (du_dc, du_dr, _), *_ = np.linalg.lstsq(design, u, rcond=None)
    (dv_dc, dv_dr, _), *_ = np.linalg.lstsq(design, v, rcond=None)
    assert du_dc > 0 and abs(du_dr) < du_dc, "image x must run to the right on screen"
    assert dv_dr > 0 and abs(dv_dc) < dv_dr, "image y (down) must run down the screen"


def test_hall_camera_stands_on_the_paintings_bottom_side():
    spec = builtin_room("hall", [PaintingSize("a", 200, 100, 1.0, 0.5)], count=3)
    eye = np.array(spec.camera_eye)
    for slot in spec.paintings:
        bottom_edge_z = slot.origin[2] + slot.height_m * slot.v_axis[2]
        assert eye[2] > bottom_edge_z

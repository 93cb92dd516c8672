"""`--look-at` in the built-in rooms: the painting is centred and reads upright and
unmirrored (the gradient painting: red rises along image x, blue along image y, down), and
the default distance keeps the camera inside the room. References: the pinhole geometry of
the still (where the painting's centre and edges land) and the room's own box."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from gigascroll.cli import main
from gigascroll.exhibit.cameras import fill_distance, look_at, room_bounds
from gigascroll.gallery import builtin_room

from gallery_checks import gradient_pack


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return gradient_pack(tmp_path_factory.mktemp("look") / "g.pack", size=(256, 128))


def still(pack, tmp_path, room, which, w=160, h=120):
    out = tmp_path / f"{room}-{which}.png"
    assert main(["render", "--room", room, "--pack", str(pack.path), "--look-at", which,
                 "--lighting", "unlit", "--width", str(w), "--height", str(h), "-o",
                 str(out)]) == 0
    return np.asarray(Image.open(out))[..., :3].astype(int)


def painting_mask(img):
    # The gradient painting: red or blue well above its fixed green (the walls are grey).
    return np.maximum(img[..., 0], img[..., 2]) - img[..., 1] > 30


@pytest.mark.parametrize("room", ["scroll", "hall"])
def test_look_at_centres_an_upright_unmirrored_painting(pack, tmp_path, room):
    img = still(pack, tmp_path, room, "gradient" if room == "scroll" else "0")
    m = painting_mask(img)
    ys, xs = np.nonzero(m)
    assert m[60, 80], "the view's centre is not on the painting"
    assert abs((xs.min() + xs.max() + 1) / 2 - 80) <= 2
    # Unmirrored: red grows to the right; upright: blue grows downward.
    cx, cy = (xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2
    left, right = img[m & (np.arange(160) < cx)[None, :]], img[m & (np.arange(160) > cx)[None, :]]
    top = img[m & (np.arange(120) < cy)[:, None]]
    bottom = img[m & (np.arange(120) > cy)[:, None]]
    assert right[:, 0].mean() > left[:, 0].mean() + 20
    assert bottom[:, 2].mean() > top[:, 2].mean() + 10


def test_the_scroll_fills_80_percent_of_the_width(pack, tmp_path):
    img = still(pack, tmp_path, "scroll", "0")
    xs = np.nonzero(painting_mask(img).any(axis=0))[0]
    assert (xs.max() + 1 - xs.min()) == pytest.approx(0.8 * 160, abs=2)


def test_the_default_distance_stays_in_the_room(pack):
    # A view much wider than tall puts the 80 % distance of the scroll (3.2 m x 1.6 m) far
    # behind the 4 m deep room's far wall: the camera stops 5 cm short of it instead.
    room = builtin_room("scroll", pack)
    slot = room.paintings[0]
    assert fill_distance(slot.width_m, slot.height_m, 10.0, 1.0) > 4.0
    eye, target = look_at(slot, None, 10.0, 1.0, room_bounds(room))
    lo, hi = room_bounds(room)
    assert lo[2] + 0.049 < eye[2] < target[2]
    assert eye[2] == pytest.approx(lo[2] + 0.05)
    # A given distance is taken as is.
    eye, _ = look_at(slot, 7.0, 10.0, 1.0, room_bounds(room))
    assert eye[2] == pytest.approx(target[2] - 7.0)

"""Exhibitions: a small show (two tiny synthetic paintings in a floor plan room) builds,
renders and hangs where its file says; bad files are one line naming the file and the key
(exit 2); a second build reuses the pack.

References: the slots' geometry is worked out by hand from the file's numbers (wall
directions, the 5 mm gap, the frame's depth); the look-at still is checked against the
pinhole camera's geometry (a painting centred and filling 80 % of the view)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gigascroll.cli import main
from gigascroll.exhibit import ExhibitionError, load_exhibition
from gigascroll.exhibit.build import build_show
from gigascroll.exhibit.floor_plan import build_room
from gigascroll.exhibit.schema import schema
from gigascroll.exhibit.show import open_show

SHOW = """
title = "Two studies"
[room]
walls = [[0, 0], [6, 0], [6, 4], [0, 4]]
height_m = 3.0

[[paintings]]
title = "Red study"
artist = "A. Painter"
date = "1901"
rights = "https://creativecommons.org/publicdomain/zero/1.0/"
image = "red.png"
width_cm = 80
height_cm = 60
hang = { wall = 0, along_m = 2.0 }
frame = { width_cm = 4, depth_cm = 3 }

[[paintings]]
title = "Blue study"
image = "blue.png"
width_cm = 40
height_cm = 60
hang = { wall = 1, along_m = 2.0, centre_height_cm = 150 }
"""


def write_images(d: Path) -> None:
    red = np.zeros((48, 64, 3), np.uint8)
    red[..., 0] = 220
    blue = np.zeros((60, 40, 3), np.uint8)
    blue[..., 2] = 220
    Image.fromarray(red).save(d / "red.png")
    Image.fromarray(blue).save(d / "blue.png")


@pytest.fixture
def show_dir(tmp_path):
    write_images(tmp_path)
    (tmp_path / "show.toml").write_text(SHOW)
    return tmp_path


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("exhibit")
    write_images(d)
    (d / "show.toml").write_text(SHOW)
    assert main(["exhibit", "build", str(d / "show.toml"), "-o", str(d / "show"), "--no-bake"]) == 0
    return d


def cli_error(capsys, argv) -> str:
    """Runs the CLI expecting exit 2 with one error line; returns the line."""
    capsys.readouterr()
    assert main(argv) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1, err
    return err[0]


def test_slots_are_the_files_numbers(show_dir):
    ex = load_exhibition(show_dir / "show.toml")
    room = build_room(ex)
    red, blue = room.paintings[0], room.paintings[1]
    # Physical sizes exactly cm / 100.
    assert (red.width_m, red.height_m) == (80 / 100, 60 / 100)
    assert (blue.width_m, blue.height_m) == (40 / 100, 60 / 100)
    # Wall 0 runs from (0, 0) to (6, 0): the room is on its +z side; the painting's centre is
    # 2.0 m along at 1.45 m (the museum default), 5 mm + the frame's 3 cm off the wall, image x
    # to the right of a visitor looking toward -z (+x), image y down.
    assert red.origin == pytest.approx((2.0 - 0.4, 1.45 + 0.3, 0.005 + 0.03), abs=1e-12)
    assert red.u_axis == (1.0, 0.0, 0.0) and red.v_axis == (0.0, -1.0, 0.0)
    # Wall 1 runs from (6, 0) to (6, 4): the room on its -x side, the visitor looks toward +x,
    # whose right is +z; centre 2.0 m along at 1.50 m.
    assert blue.origin == pytest.approx((6 - 0.005, 1.5 + 0.3, 2.0 - 0.2), abs=1e-12)
    assert blue.u_axis == pytest.approx((0.0, 0.0, 1.0))
    # The labels come after the paintings, beside them on the visitor's right.
    assert [s.name for s in room.paintings[2:]] == ["label-red-study", "label-blue-study"]
    label = room.paintings[2]
    assert label.origin[0] == pytest.approx(2.0 + 0.44 + 0.10)  # frame's edge + 10 cm gap
    assert label.origin[1] - label.height_m == pytest.approx(1.45 - 0.34)  # bottoms level


def test_built_show_opens_with_the_same_room(built):
    show = open_show(built / "show")
    again = build_room(load_exhibition(built / "show.toml"))
    assert [(s.origin, s.width_m, s.height_m) for s in show.room.paintings] == \
        [(s.origin, s.width_m, s.height_m) for s in again.paintings]
    assert [p.title for p in show.exhibition.paintings] == ["Red study", "Blue study"]
    assert show.exhibition.paintings[0].artist == "A. Painter"
    names = [p.name for p in show.pack.paintings]
    assert names == ["red-study", "blue-study", "label-red-study", "label-blue-study"]
    assert len(show.tour.time) >= 4
    # The published schema is the one the package validates with.
    assert schema()["$id"].endswith("exhibition-1.json")


def coloured_box(img: np.ndarray, channel: int) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) of the pixels where `channel` dominates."""
    c = img[..., :3].astype(int)
    others = [k for k in range(3) if k != channel]
    mask = (c[..., channel] > 60) & (c[..., channel] > 2 * c[..., others].max(axis=2) + 10)
    ys, xs = np.nonzero(mask)
    assert xs.size, "the painting is not in view"
    return xs.min(), xs.max() + 1, ys.min(), ys.max() + 1


@pytest.mark.parametrize("which, channel, limit", [("Red study", 0, "both"), ("1", 2, "height")])
def test_look_at_centres_the_painting(built, tmp_path, which, channel, limit):
    out = tmp_path / "still.png"
    assert main(["render", "--exhibition", str(built / "show"), "--look-at", which,
                 "--lighting", "unlit", "--width", "160", "--height", "120", "-o", str(out)]) == 0
    img = np.asarray(Image.open(out))
    x0, x1, y0, y1 = coloured_box(img, channel)
    assert (x0 + x1) / 2 == pytest.approx(80, abs=1.0)
    assert (y0 + y1) / 2 == pytest.approx(60, abs=1.0)
    # The default distance fills 80 % of the view: a 4:3 painting in a 4:3 view both ways,
    # the 2:3 one its height.
    assert (y1 - y0) == pytest.approx(0.8 * 120, abs=2)
    if limit == "both":
        assert (x1 - x0) == pytest.approx(0.8 * 160, abs=2)


def test_look_at_distance_scales_the_painting(built, tmp_path):
    # At twice the default distance the painting is half as tall in the view (pinhole).
    out = tmp_path / "far.png"
    from gigascroll.exhibit.cameras import fill_distance
    d = fill_distance(0.8, 0.6, 60.0, 160 / 120)
    assert main(["render", "--exhibition", str(built / "show"), "--look-at", "Red study",
                 "--distance", str(2 * d), "--lighting", "unlit", "--width", "160",
                 "--height", "120", "-o", str(out)]) == 0
    x0, x1, y0, y1 = coloured_box(np.asarray(Image.open(out)), 0)
    assert (y1 - y0) == pytest.approx(0.4 * 120, abs=2)


def test_second_build_reuses_the_pack(show_dir):
    out = show_dir / "show"
    first = build_show(show_dir / "show.toml", out)
    manifest = out / "paintings.pack" / "manifest.json"
    ino = manifest.stat().st_ino
    second = build_show(show_dir / "show.toml", out)
    assert first["packed"] and not first["reused_pack"]
    assert second["reused_pack"] and not second["packed"]
    assert json.loads((out / "build.json").read_text())["reused_pack"] is True
    assert manifest.stat().st_ino == ino  # the same file (hard-linked), not packed again
    # A changed image is packed again.
    img = np.zeros((48, 64, 3), np.uint8)
    img[..., 0] = 200
    Image.fromarray(img).save(show_dir / "red.png")
    assert build_show(show_dir / "show.toml", out)["packed"]


def test_a_directory_not_made_by_exhibit_build_is_not_replaced(show_dir, capsys):
    (show_dir / "other").mkdir()
    (show_dir / "other" / "keep.txt").write_text("mine")
    line = cli_error(capsys, ["exhibit", "build", str(show_dir / "show.toml"), "-o",
                              str(show_dir / "other"), "--no-bake"])
    assert "other" in line and (show_dir / "other" / "keep.txt").read_text() == "mine"


BAD = [
    ("title = \n", "TOML syntax error", "line 1"),
    (SHOW.replace("width_cm = 40", "width_cm = -3"), "paintings[1].width_cm", "> 0"),
    (SHOW.replace("width_cm = 40", "width_cm = nan"), "paintings[1].width_cm", "finite"),
    (SHOW.replace('artist = "A. Painter"', 'artiste = "A. Painter"'), "paintings[0]", "artiste"),
    (SHOW.replace("height_m = 3.0", ""), None, None),  # a default height: fine
    (SHOW.replace("width_cm = 80\nheight_cm = 60", "width_cm = 800\nheight_cm = 600"),
     "paintings[0].hang", "6 m long"),
    (SHOW.replace("wall = 1, along_m = 2.0", "wall = 0, along_m = 2.3"),
     "paintings[1].hang", "overlaps"),
    (SHOW.replace("width_cm = 80\nheight_cm = 60", "width_cm = 80\nheight_cm = 80"),
     "paintings[0].width_cm / height_cm", "64 x 48 px"),
    (SHOW.replace('image = "blue.png"', 'image = "nope.png"'), "paintings[1].image",
     "expected an existing image file"),
    (SHOW.replace("wall = 1,", "wall = 7,"), "paintings[1].hang.wall", "0..3"),
    (SHOW.replace("[room]\nwalls", "[room]\nbuiltin = \"hall\"\nwalls"), "room", "exactly one of"),
]


@pytest.mark.parametrize("text, key, expected", BAD)
def test_bad_files_are_one_line_naming_file_and_key(show_dir, capsys, text, key, expected):
    f = show_dir / "show.toml"
    f.write_text(text)
    argv = ["exhibit", "build", str(f), "-o", str(show_dir / "out"), "--no-bake"]
    if key is None:
        assert main(argv) == 0
        return
    line = cli_error(capsys, argv)
    assert str(f) in line and key in line and expected in line, line
    assert not (show_dir / "out").exists()


def test_a_painting_too_big_names_both_sizes(show_dir):
    f = show_dir / "show.toml"
    f.write_text(SHOW.replace("width_cm = 40\nheight_cm = 60", "width_cm = 240\nheight_cm = 360"))
    with pytest.raises(ExhibitionError) as e:
        build_room(load_exhibition(f))
    msg = str(e.value)
    assert "2.4 m x 3.6 m" in msg and "4 m long x 3 m high" in msg


def test_unknown_look_at_title_is_one_line(built, tmp_path, capsys):
    line = cli_error(capsys, ["render", "--exhibition", str(built / "show"), "--look-at",
                              "Green study", "-o", str(tmp_path / "x.png")])
    assert "Green study" in line and "Red study" in line
    line = cli_error(capsys, ["render", "--exhibition", str(built / "show"), "--look-at", "5",
                              "-o", str(tmp_path / "x.png")])
    assert "2 paintings" in line
    line = cli_error(capsys, ["render", "--exhibition", str(tmp_path), "-o",
                              str(tmp_path / "x.png")])
    assert "not a show" in line


def test_table_painting_faces_up_and_reads_from_the_visitors_side(show_dir):
    f = show_dir / "show.toml"
    f.write_text(SHOW.replace("hang = { wall = 1, along_m = 2.0, centre_height_cm = 150 }",
                              "hang = { on = \"vitrine\", position_m = [3, 2], tilt_deg = 30 }"))
    room = build_room(load_exhibition(f))
    s = room.paintings[1]
    u, v = np.array(s.u_axis), np.array(s.v_axis)
    centre = np.array(s.origin) + u * s.width_m / 2 + v * s.height_m / 2
    assert centre == pytest.approx([3.0, 0.9, 2.0])
    # v x u, the side the image reads from, points up and toward +z (the visitor), 30 degrees
    # from vertical.
    n = np.cross(v, u)
    assert n == pytest.approx([0.0, np.cos(np.radians(30)), np.sin(np.radians(30))])
    assert any(x.name == "tables" for x in room.surfaces)


def test_builtin_room_keeps_physical_sizes(show_dir):
    f = show_dir / "show.toml"
    text = SHOW.replace("walls = [[0, 0], [6, 0], [6, 4], [0, 4]]\nheight_m = 3.0",
                        "builtin = \"hall\"")
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(("hang", "frame")))
    f.write_text(text)
    room = build_room(load_exhibition(f))
    assert [(s.width_m, s.height_m) for s in room.paintings] == [(0.8, 0.6), (0.4, 0.6)]


def test_the_docs_example_is_valid(tmp_path):
    # docs/exhibitions.md's example loads and builds its room (its images made here).
    docs = Path(__file__).resolve().parents[2] / "docs" / "exhibitions.md"
    example = docs.read_text().split("```toml\n", 1)[1].split("```", 1)[0]
    write_images(tmp_path)
    (tmp_path / "example.toml").write_text(example)
    room = build_room(load_exhibition(tmp_path / "example.toml"))
    assert [s.name for s in room.paintings] == ["red-study", "blue-study", "label-red-study"]
    assert room.lights[0].kelvin == 3000


def test_a_pack_is_used_as_is(show_dir):
    from gigascroll.pack import build_pack
    red = np.asarray(Image.open(show_dir / "red.png"))
    blue = np.asarray(Image.open(show_dir / "blue.png"))
    build_pack([red, blue], show_dir / "mine.pack", names=["r", "b"])
    text = SHOW.replace('image = "red.png"', 'pack = "mine.pack"\npainting = "r"')
    text = text.replace('image = "blue.png"', 'pack = "mine.pack"\npainting = 1')
    (show_dir / "show.toml").write_text("labels = false\n" + text)
    record = build_show(show_dir / "show.toml", show_dir / "show")
    assert not record["packed"] and not record["reused_pack"]
    assert not (show_dir / "show" / "paintings.pack").exists()
    show = open_show(show_dir / "show")
    assert Path(show.pack.path).resolve() == (show_dir / "mine.pack").resolve()
    assert [s.painting for s in show.room.paintings] == ["r", "b"]  # no labels asked for
    # With the labels (the default) the pack is merged into the show's own, which holds them.
    (show_dir / "show.toml").write_text(text)
    assert build_show(show_dir / "show.toml", show_dir / "show1")["packed"]
    assert [s.painting for s in open_show(show_dir / "show1").room.paintings] == [
        "red-study", "blue-study", "label-red-study", "label-blue-study"]
    # Mixing images with a pack merges them into the show's pack (test_exhibit_merge.py).
    (show_dir / "show.toml").write_text(SHOW.replace('image = "red.png"',
                                                     'pack = "mine.pack"'))
    assert build_show(show_dir / "show.toml", show_dir / "show2")["packed"]


def test_a_room_file_with_the_physical_sizes(tmp_path):
    from gigascroll.room.example import EXAMPLE_PAINTINGS, write_example_room
    write_example_room(tmp_path / "room.glb")
    Image.fromarray(np.full((40, 60, 3), 150, np.uint8)).save(tmp_path / "land.png")
    Image.fromarray(np.full((60, 20, 3), 90, np.uint8)).save(tmp_path / "scroll.png")
    assert set(EXAMPLE_PAINTINGS) == {"landscape", "hanging_scroll"}
    text = """
[room]
file = "room.glb"
[[paintings]]
title = "A landscape"
name = "landscape"
image = "land.png"
width_cm = 150
height_cm = 100
[[paintings]]
title = "A hanging scroll"
name = "hanging_scroll"
image = "scroll.png"
width_cm = SCROLL_W
height_cm = 100
"""
    # The example's placeholders: the landscape 1.5 m x 1 m, the scroll 1 m tall at 1:3.
    (tmp_path / "ok.toml").write_text(text.replace("SCROLL_W", str(100 / 3)))
    record = build_show(tmp_path / "ok.toml", tmp_path / "show")
    assert record["packed"]
    slots = open_show(tmp_path / "show").room.paintings
    assert sorted(round(s.width_m, 4) for s in slots) == [0.3333, 1.5]
    # A physical size the room file's placeholder does not have: an error naming both.
    (tmp_path / "bad.toml").write_text(text.replace("SCROLL_W", str(100 / 3)).replace(
        "width_cm = 150\nheight_cm = 100", "width_cm = 120\nheight_cm = 80"))
    with pytest.raises(ExhibitionError, match=r"paintings\[0\].width_cm / height_cm: expected "
                                              r"the room file's slot 1.5 m x 1 m, got 1.2 m x 0.8 m"):
        build_show(tmp_path / "bad.toml", tmp_path / "show2")


def test_a_killed_build_leaves_nothing_that_looks_like_a_show(show_dir):
    import signal
    import subprocess
    import sys
    import time
    # Killed outright while packing a larger image: no show; the next build removes its
    # temporary and succeeds.
    big = np.zeros((1800, 2400, 3), np.uint8)
    big[..., 0] = 200
    Image.fromarray(big).save(show_dir / "red.png")
    p = subprocess.Popen([sys.executable, "-m", "gigascroll", "exhibit", "build",
                          str(show_dir / "show.toml"), "-o", str(show_dir / "show"), "--no-bake"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(300):
        if any(x.name.startswith("show.tmp-") for x in show_dir.iterdir()):
            break
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert not (show_dir / "show").exists()
    with pytest.raises(ExhibitionError):
        open_show(show_dir / "show")
    build_show(show_dir / "show.toml", show_dir / "show")
    assert open_show(show_dir / "show").pack.paintings[0].width == 2400
    assert not any(x.name.startswith("show.tmp-") for x in show_dir.iterdir())


TOUR = """
[tour]
max_speed_mps = 1.0
keyframes = [
  { position = [2.0, 1.6, 2.0], target = [2.0, 1.45, 0.0], time = 0.0 },
  { position = [4.0, 1.6, 2.0], target = [6.0, 1.5, 2.0], time = TIME },
]
"""


def test_the_files_tour_is_the_shows(show_dir):
    f = show_dir / "show.toml"
    f.write_text(SHOW + TOUR.replace("TIME", "4.0"))
    build_show(f, show_dir / "show")
    tour = open_show(show_dir / "show").tour
    assert tour.time.tolist() == [0.0, 4.0]
    assert tour.position[1].tolist() == [4.0, 1.6, 2.0]
    # 2 m in 1 s is faster than walking: an error naming the keyframe, nothing built.
    f.write_text(SHOW + TOUR.replace("TIME", "1.0"))
    with pytest.raises(ExhibitionError, match=r"show.toml: tour: tour keyframe 0 .* faster"):
        build_show(f, show_dir / "show2")
    f.write_text(SHOW + TOUR.replace("TIME", "-1"))
    with pytest.raises(ExhibitionError, match=r"tour.keyframes\[1\].time: expected a number >= 0"):
        build_show(f, show_dir / "show2")
    assert not (show_dir / "show2").exists()


def test_the_bake_is_the_one_serve_looks_for(show_dir):
    # exhibit build bakes the light into show/bake/KEY.glb under serve's cache key, so
    # `serve --exhibition` starts without baking.
    from types import SimpleNamespace

    from gigascroll.commands.serve import _cache_dir
    from gigascroll.serve import pack_hash
    assert main(["exhibit", "build", str(show_dir / "show.toml"), "-o", str(show_dir / "show")]) == 0
    show = open_show(show_dir / "show")
    record = json.loads((show_dir / "show" / "build.json").read_text())
    assert (show_dir / "show" / record["bake"]["glb"]).is_file()
    where = _cache_dir(SimpleNamespace(cache_dir=None), show, pack_hash(show.pack))
    assert where == show_dir / "show" / "bake"

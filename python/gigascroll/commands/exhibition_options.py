"""The options `render`, `gallery`, `view` and `serve` share for shows and cameras:
`--exhibition DIR` (a show of `exhibit build`, in place of PACK --room) and `--look-at
TITLE|N [--distance M]` (a camera in front of one painting: exhibit/cameras.py)."""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import UserError

__all__ = ["add_exhibition_option", "add_look_at_options", "open_exhibition", "look_at_pose",
           "headset_view"]


def add_exhibition_option(p) -> None:
    p.add_argument("--exhibition", metavar="DIR", default=None,
                   help="a show built by `gigascroll exhibit build` (its pack, room and tour; "
                        "in place of PACK and --room)")


def add_look_at_options(p) -> None:
    p.add_argument("--look-at", metavar="TITLE|N", default=None,
                   help="stand in front of one painting (its title in a show, a slot's name, "
                        "or its index), centred, looking at its centre")
    p.add_argument("--distance", type=float, default=None, metavar="M",
                   help="with --look-at: metres from the painting (default: where it fills "
                        "80%% of the view's width or height)")


def is_pack_dir(path) -> bool:
    """Whether `path` is a tile pack's directory (it holds the pack's manifest)."""
    return (Path(path) / "manifest.json").is_file()


def require_pack_dir(path) -> Path:
    """`path` as a Path; UserError when it is no tile pack's directory."""
    if not is_pack_dir(path):
        raise UserError(f"{path} is not a tile pack (no manifest.json)")
    return Path(path)


def open_exhibition(args, pack_option: str = "pack", room_default=None):
    """The Show of --exhibition (None without it); UserError when it is not one, or when
    PACK or --room are given too (room_default: the command's --room default, not counted)."""
    if getattr(args, "exhibition", None) is None:
        return None
    if getattr(args, pack_option, None):
        raise UserError(f"--exhibition brings its own pack: give --exhibition or "
                        f"{'PACK' if pack_option == 'pack' else '--' + pack_option}, not both")
    if getattr(args, "room", None) not in (None, room_default):
        raise UserError("--exhibition brings its own room: give --exhibition or --room, not both")
    from ..exhibit import ExhibitionError
    from ..exhibit.show import open_show
    try:
        return open_show(args.exhibition)
    except ExhibitionError as e:
        raise UserError(str(e)) from None


def headset_view(eye) -> tuple[float, float]:
    """(vertical field of view in degrees, aspect) of the headset's eye at resolution `eye`
    (views.exhibition.Headset: square pixels), what gallery and view show."""
    from ..views.exhibition import Headset
    hs = Headset(width=int(eye[0]), height=int(eye[1]))
    return 2 * math.degrees(math.atan(hs.tan_half_y)), hs.tan_half_x / hs.tan_half_y


def look_at_pose(args, room, show=None, fov: float = 60.0, aspect: float = 1.0):
    """(eye, target) of --look-at in `room` (None without it); --distance alone, or a name
    that is no painting's, is a UserError."""
    if args.look_at is None:
        if args.distance is not None:
            raise UserError("--distance goes with --look-at")
        return None
    if args.distance is not None and not (math.isfinite(args.distance)
                                          and 0.05 <= args.distance <= 1000):
        raise UserError(f"--distance must be in [0.05, 1000] metres, got {args.distance}")
    from ..exhibit.cameras import look_at, room_bounds, slot_index
    try:
        k = slot_index(room, args.look_at, show.titles if show is not None else None)
        return look_at(room.paintings[k], args.distance, fov, aspect, room_bounds(room))
    except ValueError as e:
        raise UserError(str(e)) from None

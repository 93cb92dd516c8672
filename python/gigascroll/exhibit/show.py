"""A built show (`exhibit build`'s directory) opened for the commands: `open_show(dir)` gives
the exhibition, the pack, the room (rebuilt from exhibition.json, the same numbers) and the
tour; `render`, `gallery`, `view` and `serve` take `--exhibition DIR` through it."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from ..outputs import has_mark
from .build import COMMAND
from .model import Exhibition, Frame, Hang, Painting
from .schema import ExhibitionError
from .tours import Tour, tour_from_dict

__all__ = ["Show", "open_show", "exhibition_from_json"]


@dataclass
class Show:
    path: Path
    exhibition: Exhibition
    pack: object        # TilePack
    pack_path: Path
    room: object        # RoomSpec
    tour: Tour

    @property
    def titles(self) -> dict:
        """title -> the painting's name in the show's pack (a slot's painting), for
        --look-at: a given pack shown as is keeps its own names."""
        return {p.title: p.pack_name for p in self.exhibition.paintings}


def exhibition_from_json(d: dict) -> Exhibition:
    """The Exhibition that Exhibition.to_dict() wrote."""
    paintings = []
    for p in d["paintings"]:
        p = dict(p)
        p["hang"] = Hang(**p["hang"]) if p.get("hang") else None
        p["frame"] = Frame(**p["frame"]) if p.get("frame") else None
        p["pixels"] = tuple(p["pixels"])
        paintings.append(Painting(**p))
    return Exhibition(**{**d, "paintings": paintings})


def open_show(path) -> Show:
    """The show in directory `path`; ExhibitionError when it is not a whole show."""
    from ..pack import TilePack
    from .floor_plan import build_room
    path = Path(path)
    if not has_mark(path, COMMAND) or not (path / "exhibition.json").is_file():
        raise ExhibitionError(f"{path}: not a show (build one with gigascroll exhibit build "
                              "EXHIBITION.toml -o DIR)")
    try:
        d = json.loads((path / "exhibition.json").read_text(encoding="utf-8"))
        ex = exhibition_from_json(d["exhibition"])
        pack_path = path / d["pack"]  # a relative name inside the show, or an absolute path
        pack = TilePack(pack_path)
        room = build_room(ex, pack)
        tour = tour_from_dict(json.loads((path / "tour.json").read_text(encoding="utf-8")),
                              str(path / "tour.json"))
    except ExhibitionError:
        raise
    except Exception as e:  # a damaged show: missing keys, a pack that went away
        raise ExhibitionError(f"{path}: cannot open the show: {' '.join(str(e).split())[:300]}") from None
    return Show(path, ex, pack, pack_path, room, tour)

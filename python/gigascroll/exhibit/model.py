"""An exhibition as Python objects: `load_exhibition(path)` reads the TOML file (tomllib),
validates it against the published schema (exhibition.schema.json) and checks what a schema
cannot: files exist, each painting's pixel aspect agrees with its physical aspect, titles are
unique, wall indices exist. Where the paintings hang, and whether they fit, is checked when
the room is built (floor_plan.py). Every error is an ExhibitionError naming the file, the key
and what was expected.

The objects are plain data for every consumer (the room builder, the build, the IIIF writer):
`Exhibition.paintings` lists `Painting`s with their metadata (title, artist, date, credit,
rights, accession), physical size (width_cm, height_cm; width_m / height_m = cm / 100 exactly),
source (an image file or a pack's painting), pixel size, and the name they get in the show's
pack (`name`)."""

from __future__ import annotations

import re
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path

from .schema import ExhibitionError, validate

__all__ = ["Exhibition", "Painting", "Hang", "Frame", "load_exhibition", "exhibition_from_dict",
           "MUSEUM_CENTRE_HEIGHT_CM", "MAX_FILE_BYTES"]

MUSEUM_CENTRE_HEIGHT_CM = 145.0   # the museum convention for a painting's centre on a wall
TABLE_HEIGHT_CM = 90.0            # a table's or vitrine's painting centre by default
DEFAULT_WALL_HEIGHT_M = 3.5
DEFAULT_ASPECT_TOLERANCE = 0.02
MAX_FILE_BYTES = 1 << 20
DEFAULT_LUX = 200.0       # the default lights' target (the built-in rooms' GALLERY_LUX)


@dataclass
class Hang:
    """Where a painting hangs: on wall `wall` with its centre `along_m` metres from the wall's
    first corner at `centre_height_m`; or `on` a table / vitrine with its centre at
    `position_m` [x, z] and `height_m`, tilted `tilt_deg` from flat, seen by a visitor looking
    along `facing_deg` (0: toward -z)."""

    wall: int | None = None
    along_m: float | None = None
    centre_height_m: float = MUSEUM_CENTRE_HEIGHT_CM / 100
    on: str | None = None
    position_m: tuple[float, float] | None = None
    height_m: float = TABLE_HEIGHT_CM / 100
    tilt_deg: float = 0.0
    facing_deg: float = 0.0


@dataclass
class Frame:
    """A frame or mount: a box `width_m` wider than the painting on each side and `depth_m`
    deep behind it (the painting sits on its front), of `albedo`."""

    width_m: float = 0.05
    depth_m: float = 0.03
    albedo: tuple[float, float, float] = (0.12, 0.09, 0.06)


@dataclass
class Painting:
    index: int
    title: str
    width_cm: float
    height_cm: float
    name: str                       # its name in the show's pack (unique)
    artist: str | None = None
    date: str | None = None
    credit: str | None = None
    rights: str | None = None
    accession: str | None = None
    image: str | None = None        # an image file (absolute)
    pack: str | None = None         # or a pack directory (absolute), used as is
    pack_painting: str | int = 0    # the pack's painting
    merged: bool = False            # its tiles copied into the show's pack under `name`
    pixels: tuple[int, int] = (0, 0)  # width, height in pixels
    hang: Hang | None = None
    frame: Frame | None = None

    @property
    def width_m(self) -> float:
        return self.width_cm / 100

    @property
    def height_m(self) -> float:
        return self.height_cm / 100

    @property
    def pack_name(self) -> str:
        """The painting's name in the pack the show shows: its own (`name`), or its name
        in the given pack when that pack is shown as is (not merged into the show's)."""
        return str(self.pack_painting) if self.pack and not self.merged else self.name

    @property
    def key(self) -> str:
        return f"paintings[{self.index}]"


@dataclass
class Exhibition:
    """A loaded exhibition file (`path`, absolute); `room` is the file's [room] table with
    relative paths resolved; `lights` the [[lights]] tables (LightSpec fields, as
    room.lights.lights_from_json reads them); `tour` the [tour] table or None."""

    path: str
    title: str
    room: dict
    paintings: list[Painting]
    lights: list = field(default_factory=list)
    tour: dict | None = None
    labels: bool = True
    aspect_tolerance: float = DEFAULT_ASPECT_TOLERANCE
    language: str = "none"   # of the titles and names: the IIIF language maps' tag
    lux: float = DEFAULT_LUX  # the default lights' target on each painting

    def painting(self, which) -> Painting:
        """A painting by title, pack name or index (int or digits); ValueError naming the
        titles otherwise."""
        return self.paintings[painting_number(self, which)]

    def to_dict(self) -> dict:
        return asdict(self)


def painting_number(ex: Exhibition, which) -> int:
    if isinstance(which, int) or (isinstance(which, str) and which.strip().isdigit()):
        k = int(which)
        if not 0 <= k < len(ex.paintings):
            raise ValueError(f"painting {k}: the exhibition has {len(ex.paintings)} paintings "
                             f"(0..{len(ex.paintings) - 1})")
        return k
    for p in ex.paintings:
        if which in (p.title, p.name):
            return p.index
    titles = ", ".join(repr(p.title) for p in ex.paintings[:10])
    raise ValueError(f"no painting titled {str(which)[:80]!r} (titles: {titles})")


def load_exhibition(path) -> Exhibition:
    """The exhibition in the TOML file `path` (see the module docstring)."""
    path = Path(path)
    where = str(path)
    try:
        if not path.is_file():
            raise ExhibitionError(f"{where}: no such exhibition file")
        if path.stat().st_size > MAX_FILE_BYTES:
            raise ExhibitionError(f"{where}: an exhibition file is at most 1 MB")
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ExhibitionError(f"{where}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except OSError as e:
        raise ExhibitionError(f"{where}: cannot read: {e.strerror or e}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ExhibitionError(f"{where}: TOML syntax error: {' '.join(str(e).split())}") from None
    except RecursionError:
        raise ExhibitionError(f"{where}: TOML syntax error: nested too deeply") from None
    return exhibition_from_dict(data, where, path.resolve().parent)


def exhibition_from_dict(data: dict, where: str, base: Path) -> Exhibition:
    """An Exhibition from the file's parsed data; relative paths are relative to `base`."""
    validate(data, where)
    room = dict(data["room"])
    if "file" in room:
        room["file"] = _existing(base, room["file"], where, "room.file", "room file")
    walls = room.get("walls")
    paintings = []
    names: set[str] = set()
    titles: dict[str, int] = {}
    for i, item in enumerate(data["paintings"]):
        key = f"paintings[{i}]"
        if item["title"] in titles:
            raise ExhibitionError(f"{where}: {key}.title: expected a title no other painting "
                                  f"has ({item['title'][:80]!r} is paintings[{titles[item['title']]}]'s)")
        titles[item["title"]] = i
        if item.get("name") in names or str(item.get("name")).startswith("label-"):
            raise ExhibitionError(f"{where}: {key}.name: expected a name no other painting "
                                  f"has, not starting with label- (the labels' names), got "
                                  f"{item['name']!r}")
        p = Painting(i, item["title"], float(item["width_cm"]), float(item["height_cm"]),
                     _unique_name(item["title"], names, item.get("name")),
                     **{k: item.get(k) for k in ("artist", "date", "credit", "rights", "accession")})
        if "image" in item:
            p.image = _existing(base, item["image"], where, f"{key}.image", "image file")
            p.pixels = _image_pixels(p.image, where, key)
        else:
            p.pack = _existing(base, item["pack"], where, f"{key}.pack", "pack", directory=True)
            p.pack_painting = item.get("painting", 0)
            p.pixels = _pack_pixels(p, where, key)
        _check_aspect(p, where, data.get("aspect_tolerance", DEFAULT_ASPECT_TOLERANCE))
        p.hang = _hang(item.get("hang"), walls, where, key)
        if "frame" in item:
            f = item["frame"]
            p.frame = Frame(f.get("width_cm", 5.0) / 100, f.get("depth_cm", 3.0) / 100,
                            tuple(f.get("albedo", Frame.albedo)))
        paintings.append(p)
    if walls is not None:
        room.setdefault("height_m", DEFAULT_WALL_HEIGHT_M)
    if "lux" in data and (walls is None or data.get("lights")):
        raise ExhibitionError(f"{where}: lux: expected only in a floor plan room without "
                              "[[lights]] (it is the default lights' target; give each light "
                              "its own lux, or the built-in rooms light themselves)")
    return Exhibition(where, data.get("title", Path(where).stem), room, paintings,
                      list(data.get("lights", [])), data.get("tour"),
                      bool(data.get("labels", True)),
                      float(data.get("aspect_tolerance", DEFAULT_ASPECT_TOLERANCE)),
                      str(data.get("language", "none")),
                      float(data.get("lux", DEFAULT_LUX)))


def _unique_name(title: str, taken: set[str], given: str | None = None) -> str:
    """The given name, or a pack painting name from a title: lower-case letters, digits and
    dashes, unique."""
    if given is not None:
        taken.add(given)
        return given
    base = re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")[:60] or "painting"
    if base.startswith("label-"):  # the labels' names
        base = f"painting-{base}"
    name, k = base, 2
    while name in taken:
        name, k = f"{base}-{k}", k + 1
    taken.add(name)
    return name


def _existing(base: Path, rel: str, where: str, key: str, what: str, directory=False) -> str:
    if "\0" in rel:
        raise ExhibitionError(f"{where}: {key}: expected a path, got a NUL character")
    p = (base / rel).resolve() if not Path(rel).is_absolute() else Path(rel)
    ok = p.is_dir() and (p / "manifest.json").is_file() if directory else p.is_file()
    if not ok:
        raise ExhibitionError(f"{where}: {key}: expected an existing {what}, {rel!r} is not one"
                              + (" (no manifest.json)" if directory and p.is_dir() else ""))
    return str(p)


def _image_pixels(image: str, where: str, key: str) -> tuple[int, int]:
    try:
        import OpenImageIO as oiio
        inp = oiio.ImageInput.open(image)
        if inp is None:
            raise OSError(" ".join(oiio.geterror().split())[:200] or "unknown format")
        spec = inp.spec()
        inp.close()
        return int(spec.width), int(spec.height)
    except (OSError, ValueError, RuntimeError) as e:
        raise ExhibitionError(f"{where}: {key}.image: expected an image file, cannot read "
                              f"{image}: {e}") from None


def _pack_pixels(p: Painting, where: str, key: str) -> tuple[int, int]:
    from ..pack import TilePack
    try:
        pack = TilePack(p.pack)
    except Exception as e:  # a corrupt pack: the reader's own error types
        raise ExhibitionError(f"{where}: {key}.pack: cannot open pack {p.pack}: {e}") from None
    names = [q.name for q in pack.paintings]
    which = p.pack_painting
    if isinstance(which, str):
        if which not in names:
            raise ExhibitionError(f"{where}: {key}.painting: expected one of the pack's "
                                  f"paintings ({', '.join(names[:10])}), got {which[:80]!r}")
        which = names.index(which)
    if not 0 <= which < len(names):
        raise ExhibitionError(f"{where}: {key}.painting: expected an index in 0..{len(names) - 1}, "
                              f"got {which}")
    q = pack.paintings[which]
    p.pack_painting = q.name
    return int(q.width), int(q.height)


def _check_aspect(p: Painting, where: str, tolerance: float) -> None:
    w, h = p.pixels
    pixel, physical = w / h, p.width_cm / p.height_cm
    if abs(pixel / physical - 1) > tolerance:
        raise ExhibitionError(
            f"{where}: {p.key}.width_cm / height_cm: expected the image's aspect {w} x {h} px "
            f"= {pixel:.4g}, got {p.width_cm:g} x {p.height_cm:g} cm = {physical:.4g} (more than "
            f"{100 * tolerance:g} % apart; aspect_tolerance sets the limit)")


def _hang(item, walls, where: str, key: str) -> Hang | None:
    if item is None:
        if walls is not None:
            raise ExhibitionError(f"{where}: {key}.hang: expected a hang table (wall and along_m, "
                                  "or on and position_m) in a floor plan room")
        return None
    if walls is None:
        raise ExhibitionError(f"{where}: {key}.hang: expected no hang: the built-in and file "
                              "rooms place their paintings themselves")
    if "wall" in item:
        if item["wall"] >= len(walls):
            raise ExhibitionError(f"{where}: {key}.hang.wall: expected a wall index in "
                                  f"0..{len(walls) - 1}, got {item['wall']}")
        return Hang(wall=item["wall"], along_m=float(item["along_m"]),
                    centre_height_m=item.get("centre_height_cm", MUSEUM_CENTRE_HEIGHT_CM) / 100)
    return Hang(on=item["on"], position_m=tuple(float(x) for x in item["position_m"]),
                height_m=item.get("height_cm", TABLE_HEIGHT_CM) / 100,
                tilt_deg=float(item.get("tilt_deg", 0.0)),
                facing_deg=float(item.get("facing_deg", 0.0)))

"""The served room: its spec, its gallery and its baked light as a cached glb.

The bake is `render --room ROOM --lighting baked`'s: the light's settings of the quality knob
(gallery/quality.py; the default level unless given) and `ROOM_LIGHTING` (the seed) over them,
so the headset shows the light of the CPU renders. The glb is cached under `cache_dir / f"{key}.glb"`, the key hashing the room spec
(surfaces, slots), the pack's content hash and the lighting options: a second start with the
same key reads the file instead of baking. It is written under a temporary name and renamed,
so a killed bake never leaves a cache entry that looks complete."""

from __future__ import annotations

import hashlib
import inspect
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import runtime
from ..gallery import Gallery, builtin_room
from ..gallery.gallery import PAINTING_REFLECTANCE
from ..room.builtin import ROOM_NAMES
from .._core import TilePack
from ..errors import expect_type
from ..room.spec import RoomSpec
from ..outputs import write_bytes
from .room_glb import room_glb

__all__ = ["ROOM_LIGHTING", "BakedRoom", "default_cache_dir", "glb_damage", "lighting_options",
           "load_room_spec", "room_key", "baked_room"]

# `gigascroll render --room`'s defaults over the knob's settings: seed=--seed (0), the default
# gather radius (commands/render.py).
ROOM_LIGHTING = {"seed": 0}
# Bumped when the glb's layout changes, so old cache entries are not served.
GLB_FORMAT = 1


def lighting_options(settings=None) -> dict:
    """What the bake's light depends on, for the cache key: the knob's LightSettings
    (None: the default level's for the fitted rooms; give the room's), ROOM_LIGHTING, the
    defaults of Gallery.light and Gallery.bake that they leave as they are (so a changed
    default is a new key) and the package's version."""
    from .. import __version__
    light, bake = ({}, {}) if settings is None else (settings.light_options(), settings.bake_options())

    def defaults(fn, skip):
        return {n: p.default for n, p in inspect.signature(fn).parameters.items()
                if p.default is not inspect.Parameter.empty and n not in skip}

    return {"light": {**defaults(Gallery.light, {"threads"}), **light, **ROOM_LIGHTING},
            "bake": {**defaults(Gallery.bake, {"threads", "progress"}), **bake}, "version": __version__}


def default_cache_dir() -> Path:
    """$XDG_CACHE_HOME/gigascroll/rooms, else ~/.cache/gigascroll/rooms."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "gigascroll" / "rooms"


def load_room_spec(room: str, pack):
    """The RoomSpec of a built-in room name or a room file (ValueError / OSError if bad)."""
    if room in ROOM_NAMES:
        return builtin_room(room, pack)
    from ..room.files import load_room

    return load_room(room, pack)


def room_key(spec, content_hash: str, lighting: dict) -> str:
    """32 hex digits hashing the room's surfaces and slots, the pack and the lighting."""
    expect_type(spec, RoomSpec, "spec")
    expect_type(content_hash, str, "content_hash")
    expect_type(lighting, dict, "lighting")
    h = hashlib.blake2b(digest_size=16, person=b"gigascroll-room")
    h.update(json.dumps({"format": GLB_FORMAT, "pack": content_hash, "lighting": lighting,
                         "name": spec.name}, sort_keys=True).encode())
    for s in spec.surfaces:
        h.update(json.dumps([s.name, [float(x) for x in s.albedo],
                             [float(x) for x in s.emission]]).encode())
        for a in (np.ascontiguousarray(s.vertices, np.float64), np.ascontiguousarray(s.triangles, np.int64)):
            h.update(str(a.shape).encode())
            h.update(a.tobytes())
    for p in spec.paintings:
        h.update(json.dumps([p.painting, [float(x) for x in p.origin], [float(x) for x in p.u_axis],
                             [float(x) for x in p.v_axis], float(p.width_m), float(p.height_m)]).encode())
    return h.hexdigest()


def _cache_folder(folder) -> Path:
    """The cache directory, made if missing; OSError at once (before a bake of minutes) when
    it is not a directory (and, by _check_writable, before a bake when it cannot be written)."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OSError(f"cache directory {folder}: {e.strerror or e}") from None
    if not folder.is_dir():
        raise OSError(f"cache directory {folder}: not a directory")
    return folder


def _check_writable(folder: Path) -> None:
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OSError(f"cache directory {folder}: not writable")


def glb_damage(path: Path) -> str | None:
    """Why the cached glb at `path` cannot be served (None when its GLB header says it is
    whole: magic, version 2 and a length equal to the file's): an entry truncated or
    replaced outside gigascroll is baked again rather than sent to every client."""
    try:
        with open(path, "rb") as f:
            header = f.read(12)
            size = os.fstat(f.fileno()).st_size
    except OSError as e:
        return f"cache entry unreadable: {e.strerror or e}"
    if len(header) < 12 or header[:4] != b"glTF":
        return "cache entry damaged: not a GLB"
    version, length = int.from_bytes(header[4:8], "little"), int.from_bytes(header[8:12], "little")
    if version != 2 or length != size:
        return f"cache entry damaged: {size} bytes, its header says {length}"
    return None


@dataclass
class BakedRoom:
    """A room ready to serve: spec, gallery, cache key, the glb's path and whether it came
    from the cache (`cache_hit`) or was baked now."""

    spec: object
    gallery: Gallery
    key: str
    glb_path: Path
    cache_hit: bool
    bake_stats: dict = field(default_factory=dict)


def _mesh_infos(gallery: Gallery, spec, lattice: dict) -> list[dict]:
    """One dict per Embree geometry (room_glb's `meshes`): names from the spec's surfaces
    that kept a triangle, in order, then the painting slots."""
    geometry, slot = lattice["geometry"], lattice["slot"]
    count = int(geometry.max()) + 1 if len(geometry) else 0
    surface_names = [s.name for s in spec.surfaces if _keeps_a_triangle(s)]
    infos = []
    for g in range(count):
        first = int(np.flatnonzero(geometry == g)[0])
        s = int(slot[first])
        if s >= 0:
            ps = spec.paintings[s]
            infos.append({"name": f"painting {s}: {ps.name or ps.painting}",
                          "albedo": (PAINTING_REFLECTANCE,) * 3, "emission": (0.0, 0.0, 0.0),
                          "slot": s, "painting": gallery.slot_paintings[s], "origin": ps.origin,
                          "u_axis": ps.u_axis, "v_axis": ps.v_axis, "width_m": ps.width_m,
                          "height_m": ps.height_m})
        else:
            name = surface_names[g] if g < len(surface_names) else f"surface {g}"
            infos.append({"name": name, "albedo": lattice["albedo"][first],
                          "emission": lattice["emission"][first]})
    return infos


def _keeps_a_triangle(surface) -> bool:
    """Whether the core keeps any of the surface's triangles (Gallery::add_surface's test:
    a positive finite float cross product)."""
    v = np.asarray(surface.vertices, np.float32)
    t = np.asarray(surface.triangles, np.int64)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    with np.errstate(all="ignore"):
        length = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    return bool(np.any(np.isfinite(length) & (length > 0)))


def bake_glb(gallery: Gallery, spec, pack, threads: int = 0, settings=None) -> tuple[bytes, dict]:
    """Lights and bakes the gallery as `render --room --lighting baked` does (at `settings`,
    the knob's LightSettings; None: the room's at the default level), and returns (the glb,
    the lighting stats)."""
    from ..gallery.quality import light_settings

    settings = light_settings(spec) if settings is None else settings
    # The photons read the paintings' pinned coarse levels: any VT of the pack will do.
    gallery.light(runtime.VirtualTexture(pack, (30, 30)), threads=threads,
                  **{**settings.light_options(), **ROOM_LIGHTING})
    gallery.bake(threads=threads, **settings.bake_options())
    lattice = gallery._bake_lattice()
    return room_glb(lattice, _mesh_infos(gallery, spec, lattice)), dict(gallery.stats)


def baked_room(room: str, pack, content_hash: str, cache_dir: Path | None = None,
               threads: int = 0, announce=None, spec: RoomSpec | None = None,
               settings=None) -> BakedRoom:
    """The room `room` (built-in name or file) with the pack's paintings, its glb baked or
    taken from the cache. announce(text), when given, hears one line: hit or bake. `spec`:
    a RoomSpec to serve instead of `room`'s (an exhibition's). `settings`: the light's
    LightSettings (gallery/quality.py; None: the room's at the default level)."""
    expect_type(room, str, "room")
    expect_type(pack, TilePack, "pack")
    expect_type(content_hash, str, "content_hash")
    if cache_dir is not None:
        expect_type(cache_dir, (str, os.PathLike), "cache_dir")
        if not str(cache_dir).strip():
            raise ValueError("cache_dir must name a directory")
    if spec is None:
        spec = load_room_spec(room, pack)
    expect_type(spec, RoomSpec, "spec")
    gallery = Gallery.from_room(spec, pack)
    from ..gallery.quality import light_settings
    settings = light_settings(spec) if settings is None else settings
    key = room_key(spec, content_hash, lighting_options(settings))
    path = _cache_folder(cache_dir if cache_dir is not None else default_cache_dir()) / f"{key}.glb"
    damage = glb_damage(path) if path.is_file() else "cache miss"
    if damage is None:
        if announce:
            announce(f"room {spec.name}: bake cache hit ({path.name})")
        return BakedRoom(spec, gallery, key, path, True)
    _check_writable(path.parent)
    if announce:
        announce(f"room {spec.name}: baking the light ({damage}, {path.name})")
    data, stats = bake_glb(gallery, spec, pack, threads, settings)
    write_bytes(path, data, durable=True)  # a temporary name, then renamed
    if announce:
        announce(f"room {spec.name}: baked {stats['bake_points']} points in "
                 f"{stats['photon_seconds'] + stats['build_seconds'] + stats['bake_seconds']:.1f} s, "
                 f"{len(data) / 1e6:.1f} MB cached")
    return BakedRoom(spec, gallery, key, path, False, stats)

"""Merging tile packs: paintings of existing packs gathered into a new pack without decoding
or re-encoding a tile (an exhibition that mixes image files and packs, or several packs).

`merge_packs(items, out)` takes (name, pack directory, painting) triples: painting `name` of
the new pack is that pack's painting (its name or index). The packs must share tile size,
border and codec (tiles are copied as stored); a ValueError names both settings otherwise.

Tile data: a version-2 painting's tile file holds exactly its tiles and is hard-linked into
the new pack where the file system allows (else copied), its offsets kept; a version-1
pack's single tiles.bin is cut into one file per painting. Every stored tile is read once:
its checksum is verified against the source entry (OSError naming the pack and the tile)
and computed again for its new key (a version-2 checksum is seeded with the tile's key,
whose painting field changes with the painting's place). A stored painting named twice (a
painting and its instance, one pack given by two paths, the same painting twice) is stored
once and the others become instances of it (build_pack's instances): the new pack holds
each distinct painting's tiles once.

The index and manifest are written by the core's PackBuilder.assemble, the sharded build's
merge (each painting a shard: tiles-NNNNN.bin and shard-NNNNN.idx), which checks each index
against the painting's geometry and validates the manifest; the pack is built under a
temporary name beside `out` and renamed into place, so a failed merge leaves no pack."""

from __future__ import annotations

import json
import os
import shutil
import struct
from pathlib import Path

import numpy as np

from .. import _core
from .._core import painting_geometry
from ..outputs import check_output, replace_dir, temp_dir
from .build import _is_pack_dir, plan_layout
from .reader import _ENTRY, _HEADER, _INDEX_MAGIC, _TILES_MAGIC, PurePack, tile_seed

__all__ = ["merge_packs"]

_STORED = 1
_VERSION = 2


def merge_packs(items, out, *, force: bool = False, layout: str = "brkga", seed: int = 0,
                progress: bool = False):
    """Builds the pack `out` from `items`, (name, pack directory, painting) triples (painting:
    a name or an index in that pack), and returns it opened (TilePack). See the module
    docstring. ValueError for bad items or packs whose settings differ; OSError for an
    unreadable or corrupt source pack. `progress`: a bar counting the tiles verified."""
    import xxhash  # noqa: F401  (the reader's dependency: fail before any work)
    items = _check_items(items)
    out = Path(out)
    check_output(out, force=force, directory=True, owned=_is_pack_dir, what="a tile pack")
    packs: dict[str, PurePack] = {}
    try:
        resolved = [_resolve(packs, name, path, which) for name, path, which in items]
        settings = _common_settings(packs, items)
        stored, instances = _dedupe(resolved)
        return _assemble(packs, stored, instances, out, settings, layout, seed, progress)
    finally:
        for p in packs.values():
            p.close()


def _check_items(items) -> list[tuple[str, str, int | str]]:
    if isinstance(items, (str, bytes, dict)) or items is None:
        raise ValueError("items must be a list of (name, pack, painting) triples")
    try:
        items = list(items)
    except TypeError:
        raise ValueError(f"items must be a list of (name, pack, painting) triples, not "
                         f"{type(items).__name__}") from None
    out, names = [], set()
    for item in items:
        if not (isinstance(item, (tuple, list)) and len(item) == 3):
            raise ValueError(f"item {item!r} is not a (name, pack, painting) triple")
        name, path, which = item
        if not isinstance(name, str) or not name or "\0" in name \
                or any(0xD800 <= ord(c) <= 0xDFFF for c in name):
            raise ValueError(f"painting name {name!r} is not a non-empty UTF-8 text")
        if name in names:
            raise ValueError(f"painting name '{name}' is given twice")
        names.add(name)
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(f"painting '{name}': pack must be a path, not {type(path).__name__}")
        if isinstance(which, bool) or not isinstance(which, (int, np.integer, str)):
            raise ValueError(f"painting '{name}': the pack's painting must be a name or an "
                             f"index, not {type(which).__name__}")
        out.append((name, os.fspath(path), which))
    if not out:
        raise ValueError("no paintings to merge")
    if len(out) > _core.MAX_PACK_PAINTINGS:
        raise ValueError(f"{len(out)} paintings: a pack holds at most "
                         f"{_core.MAX_PACK_PAINTINGS} (the tile key's 16-bit field)")
    return out


def _resolve(packs: dict, name: str, path: str, which) -> tuple[str, str, int]:
    """(name, the pack's real path, the index of the stored painting that holds the tiles)."""
    real = os.path.realpath(path)
    if real not in packs:
        import warnings
        with warnings.catch_warnings():  # a version-1 pack is merged into version 2
            warnings.simplefilter("ignore", UserWarning)
            packs[real] = PurePack(real)
    pack = packs[real]
    names = [p.name for p in pack.paintings]
    if isinstance(which, str):
        if which not in names:
            raise ValueError(f"painting '{name}': pack {path} has no painting named "
                             f"{which[:80]!r} (it has {', '.join(names[:10])})")
        index = names.index(which)
    else:
        index = int(which)
        if not 0 <= index < len(names):
            raise ValueError(f"painting '{name}': pack {path} has paintings 0..{len(names) - 1}, "
                             f"not {index}")
    source = pack.paintings[index].instance_of
    return name, real, index if source is None else source


def _common_settings(packs: dict, items) -> dict:
    seen = {}
    for real, pack in packs.items():
        s = {"tile_size": pack.tile_size, "border": pack.border, "codec": pack.codec}
        for other, t in seen.items():
            if t != s:
                raise ValueError(
                    f"packs {other} and {real} differ in tile size, border or codec "
                    f"({_show(t)} and {_show(s)}): tiles are copied as stored, so merged "
                    "packs must share them")
        seen[real] = s
    return next(iter(seen.values()))


def _show(s: dict) -> str:
    return f"tile {s['tile_size']}, border {s['border']}, {s['codec']}"


def _dedupe(resolved):
    """The stored paintings [(name, pack, index)] in first-use order and the instances
    [(name, stored position)]."""
    stored, instances, where = [], [], {}
    for name, real, index in resolved:
        key = (real, index)
        if key in where:
            instances.append((name, where[key]))
        else:
            where[key] = len(stored)
            stored.append((name, real, index))
    return stored, instances


def _assemble(packs, stored, instances, out: Path, settings, layout, seed, progress=False):
    tile, border, codec = settings["tile_size"], settings["border"], settings["codec"]
    src = [packs[real].paintings[i] for _, real, i in stored]
    sizes = [painting_geometry(p.width, p.height, tile, border)["table_size"] for p in src]
    sizes += [sizes[j] for _, j in instances]
    table_w, table_h, offsets, info = plan_layout(sizes, layout, seed)
    tmp = temp_dir(out)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=sum(p.tile_count for p in src), unit="tile", desc="merge packs")
    try:
        for j, (_, real, index) in enumerate(stored):
            _write_shard(packs[real], index, j, tmp, bar)
        paintings = [(name, p.width, p.height, p.source, p.conversion, *offsets[j],
                      "" if p.colour is None else json.dumps(p.colour))
                     for j, ((name, _, _), p) in enumerate(zip(stored, src))]
        placed = [(name, j, *offsets[len(stored) + k]) for k, (name, j) in enumerate(instances)]
        _core.PackBuilder.assemble(tmp, tile, border, codec, paintings, table_w, table_h,
                                   json.dumps(info), instances=placed)
        for j in range(len(stored)):
            (tmp / f"shard-{j:05d}.idx").unlink()
        replace_dir(tmp, out, owned=_is_pack_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if bar is not None:
            bar.close()
    return _core.TilePack(out)


def _write_shard(pack: PurePack, p: int, j: int, directory: Path, bar=None) -> None:
    """Painting `p` of `pack` as painting `j`'s shard: its tile file (linked or copied) and
    its index, each tile's checksum verified and seeded anew."""
    pp = pack.paintings[p]
    entries = pack._entries[pp.first_entry:pp.first_entry + pp.tile_count]
    files = set(int(f) for f in np.unique(entries["file"]))
    tiles_path = directory / f"tiles-{j:05d}.bin"
    whole = pack.version >= 2 and len(files) == 1 and _file_count(pack, next(iter(files))) \
        == pp.tile_count
    new = entries.copy()
    if whole:
        _link_or_copy(Path(pack.path) / pack.tile_files[next(iter(files))], tiles_path)
    fd = None if whole else os.open(tiles_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    try:
        if fd is not None:
            os.write(fd, bytes(_HEADER.size))
        offset = _HEADER.size
        k = 0
        for level, (nx, ny) in enumerate(pp.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    data = _read_verified(pack, p, level, tx, ty)
                    new[k]["checksum"] = _xxh3(data, tile_seed(j, level, tx, ty))
                    if fd is not None:
                        _write_all(fd, data, tiles_path)
                        new[k]["offset"], new[k]["length"] = offset, len(data)
                        offset += len(data)
                    k += 1
            if bar is not None:
                bar.update(nx * ny)
        if fd is not None:
            os.pwrite(fd, _HEADER.pack(_TILES_MAGIC, _VERSION, 0, pp.tile_count,
                                       offset - _HEADER.size), 0)
            os.fsync(fd)
    finally:
        if fd is not None:
            os.close(fd)
    new["file"], new["flags"] = j, _STORED
    header = _HEADER.pack(_INDEX_MAGIC, _VERSION, _ENTRY.itemsize, len(new),
                          len(new) * _ENTRY.itemsize)
    with open(directory / f"shard-{j:05d}.idx", "wb") as f:
        f.write(header + new.tobytes())


def _file_count(pack: PurePack, file: int) -> int:
    """The tile count in the header of the pack's tile file `file`."""
    head = os.pread(pack._fds[file], _HEADER.size, 0)
    return struct.unpack_from("<Q", head, 16)[0]


def _read_verified(pack: PurePack, p: int, level: int, tx: int, ty: int) -> bytes:
    """The stored (still encoded) bytes of a tile, after its checksum was verified."""
    key, file, offset, length, checksum = pack._entry(p, level, tx, ty)
    data = os.pread(pack._fds[file], length, offset)
    if len(data) != length:
        raise OSError(f"{pack.path}: short read of tile {key}")
    if _xxh3(data, tile_seed(p, level, tx, ty) if pack.version >= 2 else 0) != checksum:
        raise OSError(f"{pack.path}: checksum mismatch in tile {key}")
    return data


def _xxh3(data: bytes, seed: int) -> int:
    import xxhash
    return xxhash.xxh3_64_intdigest(data, seed=seed)


def _write_all(fd: int, data: bytes, path: Path) -> None:
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _link_or_copy(src: Path, dst: Path) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copyfile(src, dst)

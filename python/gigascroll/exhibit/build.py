"""`exhibit build`: an exhibition file to a show directory.

show/ holds exhibition.json (the loaded exhibition: paintings with metadata and sizes, the
room, lights; `open_show` reads it back), paintings.pack (the images and wall labels packed
once), tour.json (the file's tour or the default one), bake/ (the baked light, written by the
command's `bake` hook) and build.json (what this build did: packed or reused, seconds).

Paintings given as packs: when every painting comes from one pack (each of its paintings
at most once) and no wall labels are to be hung (labels = false, or a built-in or file
room), that pack is shown as is (exhibition.json names it). Otherwise (images and packs
mixed, several packs, a pack painting shown twice, labels on a floor plan's walls, which
need a pack of the show's own) the images are packed with the given packs' tile size, border and
codec and every given pack's painting is merged in (pack.merge: its tiles copied as stored,
hard-linked where possible, never re-encoded), under the painting's own name; a painting
shown twice is stored once and the others are instances of it.

Reuse: the pack's content hash (blake2b over every image file's bytes, every label's pixels,
the painting names, the pack settings and the given packs' manifests and indexes) is kept
in exhibition.json; a later build whose hash is the same hard-links (or copies) the previous
show's pack instead of packing again.
The directory is built under a temporary name beside `out` and swapped in
(outputs.replace_dir), its mark (outputs.MARK, command "exhibit build") written again last;
only a directory with that mark, or an empty one, is replaced. Temporaries of runs killed
outright are removed by the next run (outputs.remove_stale_temps)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import time
from pathlib import Path

from ..outputs import (check_output, owned_by, remove_stale_temps, replace_dir, temp_dir,
                       write_mark, write_text)
from .floor_plan import build_room
from .labels import label_image
from .model import Exhibition, load_exhibition
from .schema import ExhibitionError
from .tours import check_inside, check_limits, default_tour, tour_from_dict, tour_to_dict

__all__ = ["COMMAND", "PACK_NAME", "build_show", "pack_inputs", "content_hash"]

COMMAND = "exhibit build"
PACK_NAME = "paintings.pack"
IIIF_NAME = "iiif"  # the IIIF Image API tiles and the Presentation 3.0 manifest
PACK_SETTINGS = {"tile_size": 128, "border": 4, "codec": "raw", "format": 1}


def pack_inputs(ex: Exhibition) -> tuple[list, list[str], list[tuple[str, str]]]:
    """The show's pack inputs of its image paintings (image paths, label arrays), their names,
    in pack order, and the instances: a painting whose image file another painting already
    shows is stored once, as an instance of that painting (its own name and place, the same
    tiles). Paintings given as packs are not inputs (merged in by _merge)."""
    inputs, names, instances, first = [], [], [], {}
    for p in ex.paintings:
        if not p.image:
            continue
        key = os.path.realpath(p.image)
        if key in first:
            instances.append((p.name, first[key]))
            continue
        first[key] = p.name
        inputs.append(p.image)
        names.append(p.name)
    if ex.labels and "walls" in ex.room:
        for p in ex.paintings:
            if p.hang is not None and p.hang.wall is not None:
                inputs.append(label_image(p))
                names.append(f"label-{p.name}")
    return inputs, names, instances


def content_hash(inputs, names, instances=(), packs=(), settings=None) -> str:
    """32 hex digits over the inputs' bytes (files streamed), the names, the instances, the
    pack settings and, for paintings given as packs, (name, pack, painting) and each such
    pack's manifest.json and index.bin (whose checksums name every tile's bytes)."""
    h = hashlib.blake2b(digest_size=16, person=b"gigascroll-show")
    h.update(json.dumps({"names": names, "settings": settings or PACK_SETTINGS,
                         **({"instances": [list(i) for i in instances]} if instances else {}),
                         **({"packs": [list(i) for i in packs]} if packs else {})
                         }).encode())
    files = list(inputs) + [os.path.join(d, f) for d in sorted({p for _, p, _ in packs})
                            for f in ("manifest.json", "index.bin")]
    for x in files:
        if isinstance(x, str):
            with open(x, "rb") as f:
                while chunk := f.read(1 << 20):
                    h.update(chunk)
        else:
            h.update(str(x.shape).encode())
            h.update(x.tobytes())
        h.update(b"\0")
    return h.hexdigest()


def _as_is_pack(ex: Exhibition) -> str | None:
    """The pack the show shows as is: the one every painting comes from, each of its
    paintings at most once, when no wall labels are to be hung (they need the show's own
    pack); None when the show packs images or merges packs."""
    packs = {os.path.realpath(p.pack) if p.pack else None for p in ex.paintings}
    if len(packs) != 1 or None in packs:
        return None
    if ex.labels and "walls" in ex.room and any(
            p.hang is not None and p.hang.wall is not None for p in ex.paintings):
        return None
    shown = [str(p.pack_painting) for p in ex.paintings]
    return ex.paintings[0].pack if len(set(shown)) == len(shown) else None


def _pack_settings(ex: Exhibition) -> dict:
    """The show pack's tile size, border and codec: PACK_SETTINGS, or the given packs' own
    (their tiles are copied as stored); ExhibitionError naming both keys when two given
    packs differ."""
    from ..pack import TilePack
    first = None
    for p in ex.paintings:
        if not p.pack:
            continue
        pack = TilePack(p.pack)
        s = {"tile_size": pack.tile_size, "border": pack.border, "codec": pack.codec}
        if first is None:
            first = (p, s)
        elif s != first[1]:
            raise ExhibitionError(
                f"{ex.path}: {p.key}.pack: expected a pack with {first[0].key}'s pack's tile "
                f"size, border and codec ({_shown(first[1])}; tiles are copied as stored, "
                f"never re-encoded), got {_shown(s)} in {p.pack}")
    return PACK_SETTINGS if first is None else {**PACK_SETTINGS, **first[1]}


def _shown(s: dict) -> str:
    return f"tile {s['tile_size']}, border {s['border']}, codec {s['codec']}"


def _merge_items(ex: Exhibition, images_pack, label_names) -> list[tuple[str, str, str]]:
    """(name in the show's pack, pack, painting) of every painting and label."""
    items = [(p.name, p.pack, str(p.pack_painting)) if p.pack else (p.name, images_pack, p.name)
             for p in ex.paintings]
    return items + [(n, images_pack, n) for n in label_names]


def _pack_show(ex: Exhibition, dst: Path, settings: dict, *, progress, threads,
               workers) -> None:
    """Packs the show's images into `dst` and merges in the paintings given as packs."""
    from ..pack import build_pack
    from ..pack.merge import merge_packs
    inputs, names, instances = pack_inputs(ex)
    options = dict(progress=progress, threads=threads, workers=workers,
                   instances=instances or None, tile_size=settings["tile_size"],
                   border=settings["border"], codec=settings["codec"])
    if not any(p.pack for p in ex.paintings):
        build_pack(inputs, dst, names=names, **options)
        return
    images = dst.parent / f"{dst.name}.images"
    try:
        if inputs:
            build_pack(inputs, images, names=names, **options)
        labels = [n for n in names if n.startswith("label-")]
        try:
            merge_packs(_merge_items(ex, str(images), labels), dst, progress=progress)
        except (OSError, ValueError) as e:
            raise ExhibitionError(f"{ex.path}: paintings: cannot merge the given packs into "
                                  f"the show's: {e}") from None
    finally:
        shutil.rmtree(images, ignore_errors=True)


def _previous(out: Path) -> dict | None:
    try:
        if (out / "exhibition.json").is_file():
            return json.loads((out / "exhibition.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        pass
    return None


def _link_tree(src: Path, dst: Path) -> None:
    """dst as a copy of src: hard links where the file system allows, else copies."""
    dst.mkdir()
    for f in src.iterdir():
        if f.is_symlink() or not f.is_file():
            raise OSError(f"{f}: not a regular file; not reused")
        try:
            os.link(f, dst / f.name)
        except OSError:
            shutil.copy2(f, dst / f.name)


def _tour(ex: Exhibition, spec):
    """The file's tour (limits checked) or the default one of the room."""
    tour = tour_from_dict(ex.tour, f"{ex.path}: tour") if ex.tour else default_tour(spec, ex)
    try:
        check_limits(tour)
        if ex.tour:
            check_inside(tour, ex)
    except ValueError as e:
        raise ExhibitionError(f"{ex.path}: tour: {e}") from None
    return tour


def _show_pack(ex: Exhibition, out: Path, tmp: Path, previous, settings, given_pack, record,
               **options):
    """(content hash, the pack's place in exhibition.json, the pack opened): the given pack
    as is, the previous build's pack when its hash is the same (hard links), or a new one
    (_pack_show). Records in `record` what was done."""
    from ..pack import TilePack
    if given_pack is not None:
        return None, given_pack, TilePack(given_pack)
    inputs, names, instances = pack_inputs(ex)
    packs = [(p.name, os.path.realpath(p.pack), str(p.pack_painting))
             for p in ex.paintings if p.pack]
    digest = content_hash(inputs, names, instances, packs, settings)
    if previous and previous.get("pack_hash") == digest \
            and (out / PACK_NAME / "manifest.json").is_file():
        _link_tree(out / PACK_NAME, tmp / PACK_NAME)
        record["reused_pack"] = True
    else:
        _pack_show(ex, tmp / PACK_NAME, settings, **options)
        record["packed"] = True
    if packs:
        record["merged_packs"] = sorted({p for _, p, _ in packs})
    return digest, PACK_NAME, TilePack(tmp / PACK_NAME)


def build_show(exhibition, out, *, bake=None, iiif_base: str | None = None,
               progress: bool = False, threads: int = 0, workers: int = 0) -> dict:
    """Builds the show of `exhibition` (a path or an Exhibition) into `out`; returns the
    build's record (build.json). `bake(gallery, spec, pack, directory)`, when given, bakes
    the light into `directory` and returns its figures. `iiif_base`, when given, is the URL
    at which the show's iiif/ folder will be served: its paintings are exported there as IIIF
    Image API tiles with a Presentation 3.0 manifest (gigascroll.iiif_exhibition).
    `workers` > 0 packs on that many Dask workers (a LocalCluster), as `pack --workers`."""
    from ..gallery import Gallery
    t0 = time.perf_counter()
    ex = exhibition if isinstance(exhibition, Exhibition) else load_exhibition(exhibition)
    out = Path(out)
    owned = owned_by(COMMAND)
    check_output(out, force=True, directory=True, owned=owned, what="a show of exhibit build")
    if iiif_base is not None:  # before any packing
        from ..iiif_presentation import check_http_uri
        try:
            iiif_base = check_http_uri(iiif_base, "the show's IIIF base URL")
        except ValueError as e:
            raise ExhibitionError(f"{ex.path}: IIIF: {e}") from None
    given_pack = _as_is_pack(ex)
    if given_pack is not None:  # labels need the show's own pack
        ex = dataclasses.replace(ex, labels=False)
    elif any(p.pack for p in ex.paintings):  # copied into the show's pack under their names
        ex = dataclasses.replace(ex, paintings=[dataclasses.replace(p, merged=bool(p.pack))
                                                for p in ex.paintings])
    settings = PACK_SETTINGS if given_pack is not None else _pack_settings(ex)
    # The room (and whether everything fits) before any packing, where it needs no pack.
    spec = None if "file" in ex.room else build_room(ex)
    tour = None if spec is None else _tour(ex, spec)
    previous = _previous(out) if owned(out) else None
    remove_stale_temps(out, COMMAND)  # what a run killed outright (SIGKILL) left beside it
    tmp = temp_dir(out, command=COMMAND)
    try:
        record = {"exhibition": ex.path, "packed": False, "reused_pack": False}
        digest, pack_path, pack = _show_pack(ex, out, tmp, previous, settings, given_pack,
                                             record, progress=progress, threads=threads,
                                             workers=workers)
        spec = spec if spec is not None else build_room(ex, pack)
        try:
            gallery = Gallery.from_room(spec, pack)
        except ValueError as e:
            raise ExhibitionError(f"{ex.path}: room: {e}") from None
        tour = tour if tour is not None else _tour(ex, spec)
        write_text(tmp / "tour.json", json.dumps(tour_to_dict(tour), indent=1) + "\n")
        write_text(tmp / "exhibition.json", json.dumps(
            {"format": 1, "pack": pack_path, "pack_hash": digest, "exhibition": ex.to_dict()},
            indent=1) + "\n")
        if bake is not None:
            (tmp / "bake").mkdir()
            record["bake"] = bake(gallery, spec, pack, tmp / "bake")
        if iiif_base is not None:
            from ..iiif_exhibition import write_exhibition_iiif
            pack_dir = tmp / PACK_NAME if given_pack is None else given_pack
            try:
                write_exhibition_iiif(pack_dir, ex.paintings, tmp / IIIF_NAME, iiif_base,
                                      label=ex.title, threads=threads, language=ex.language)
            except ValueError as e:
                raise ExhibitionError(f"{ex.path}: IIIF: {e}") from None
            record["iiif"] = f"{IIIF_NAME}/manifest.json"
        record["seconds"] = time.perf_counter() - t0
        record["paintings"] = len(ex.paintings)
        write_text(tmp / "build.json", json.dumps(record, indent=1) + "\n")
        del gallery, pack
        write_mark(tmp, COMMAND)
        replace_dir(tmp, out, owned)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return record

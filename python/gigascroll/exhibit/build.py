"""`exhibit build`: an exhibition file to a show directory.

show/ holds exhibition.json (the loaded exhibition: paintings with metadata and sizes, the
room, lights; `open_show` reads it back), paintings.pack (the images and wall labels packed
once; a painting given as a pack is not copied: exhibition.json names that pack, used as is),
tour.json (the file's tour or the default one), bake/ (the baked light, written by the
command's `bake` hook) and build.json (what this build did: packed or reused, seconds).

Reuse: the pack's content hash (blake2b over every image file's bytes, every label's pixels,
the painting names and the pack settings) is kept in exhibition.json; a later build whose
hash is the same hard-links (or copies) the previous show's pack instead of packing again.
The directory is built under a temporary name beside `out` and swapped in
(outputs.replace_dir), its mark (outputs.MARK, command "exhibit build") written again last;
only a directory with that mark, or an empty one, is replaced. Temporaries of runs killed
outright are removed by the next run (outputs.remove_stale_temps)."""

from __future__ import annotations

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
from .tours import check_limits, default_tour, tour_from_dict, tour_to_dict

__all__ = ["COMMAND", "PACK_NAME", "build_show", "pack_inputs", "content_hash"]

COMMAND = "exhibit build"
PACK_NAME = "paintings.pack"
IIIF_NAME = "iiif"  # the IIIF Image API tiles and the Presentation 3.0 manifest
PACK_SETTINGS = {"tile_size": 128, "border": 4, "codec": "raw", "format": 1}


def pack_inputs(ex: Exhibition) -> tuple[list, list[str], list[tuple[str, str]]]:
    """The show's pack inputs (image paths, label arrays), their names, in pack order, and the
    instances: a painting whose image file another painting already shows is stored once, as
    an instance of that painting (its own name and place, the same tiles)."""
    inputs, names, instances, first = [], [], [], {}
    for p in ex.paintings:
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


def content_hash(inputs, names, instances=()) -> str:
    """32 hex digits over the inputs' bytes (files streamed), the names, the instances and
    PACK_SETTINGS."""
    h = hashlib.blake2b(digest_size=16, person=b"gigascroll-show")
    h.update(json.dumps({"names": names, "settings": PACK_SETTINGS,
                         **({"instances": [list(i) for i in instances]} if instances else {})
                         }).encode())
    for x in inputs:
        if isinstance(x, str):
            with open(x, "rb") as f:
                while chunk := f.read(1 << 20):
                    h.update(chunk)
        else:
            h.update(str(x.shape).encode())
            h.update(x.tobytes())
        h.update(b"\0")
    return h.hexdigest()


def _one_pack(ex: Exhibition) -> str | None:
    """The pack every painting comes from, or None when they are images; ExhibitionError for
    a mix or several packs (the gallery shows one pack)."""
    packs = {p.pack for p in ex.paintings if p.pack}
    if not packs:
        return None
    first = next(p for p in ex.paintings if p.pack)
    for p in ex.paintings:
        if p.image:
            raise ExhibitionError(f"{ex.path}: {p.key}.image: expected a pack as "
                                  f"{first.key}'s: a show takes images or one pack, not both")
        if p.pack != first.pack:
            raise ExhibitionError(f"{ex.path}: {p.key}.pack: expected {first.key}'s pack "
                                  f"{first.pack} (a show takes one pack)")
    return first.pack


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
    except ValueError as e:
        raise ExhibitionError(f"{ex.path}: tour: {e}") from None
    return tour

def build_show(exhibition, out, *, bake=None, iiif_base: str | None = None,
               progress: bool = False, threads: int = 0, workers: int = 0) -> dict:
    """Builds the show of `exhibition` (a path or an Exhibition) into `out`; returns the
    build's record (build.json). `bake(gallery, spec, pack, directory)`, when given, bakes
    the light into `directory` and returns its figures. `iiif_base`, when given, is the URL
    at which the show's iiif/ folder will be served: its paintings are exported there as IIIF
    Image API tiles with a Presentation 3.0 manifest (gigascroll.iiif_exhibition).
    `workers` > 0 packs on that many Dask workers (a LocalCluster), as `pack --workers`."""
    from ..gallery import Gallery
    from ..pack import TilePack, build_pack
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
    given_pack = _one_pack(ex)
    # The room (and whether everything fits) before any packing, where it needs no pack.
    spec = None if "file" in ex.room else build_room(ex)
    tour = None if spec is None else _tour(ex, spec)
    previous = _previous(out) if owned(out) else None
    remove_stale_temps(out, COMMAND)  # what a run killed outright (SIGKILL) left beside it
    tmp = temp_dir(out, command=COMMAND)
    try:
        record = {"exhibition": ex.path, "packed": False, "reused_pack": False}
        if given_pack is None:
            inputs, names, instances = pack_inputs(ex)
            digest = content_hash(inputs, names, instances)
            if previous and previous.get("pack_hash") == digest \
                    and (out / PACK_NAME / "manifest.json").is_file():
                _link_tree(out / PACK_NAME, tmp / PACK_NAME)
                record["reused_pack"] = True
            else:
                build_pack(inputs, tmp / PACK_NAME, names=names, progress=progress,
                           threads=threads, workers=workers, instances=instances or None,
                           tile_size=PACK_SETTINGS["tile_size"],
                           border=PACK_SETTINGS["border"], codec=PACK_SETTINGS["codec"])
                record["packed"] = True
            pack_path = PACK_NAME
            pack = TilePack(tmp / PACK_NAME)
        else:
            digest, pack_path, pack = None, given_pack, TilePack(given_pack)
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
                                      label=ex.title, threads=threads)
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

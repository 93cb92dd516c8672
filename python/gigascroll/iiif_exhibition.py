"""An exhibition as IIIF: each painting of the show's pack exported as IIIF Image API 3.0
level-0 tiles (gigascroll.export) under one base URL, and the Presentation 3.0 manifest of
them all (gigascroll.iiif_presentation), in one directory written as every output is
(gigascroll.outputs: built under a temporary name, marked, then swapped in):

    OUT/manifest.json            id BASE/manifest.json
    OUT/<painting>/info.json     id BASE/<painting>, the canvas's image service
    OUT/<painting>/...           its tiles

Serving OUT at BASE (any static web server) makes every URL of the manifest resolve.
`gigascroll exhibit build` calls `write_exhibition_iiif` with the show's paintings."""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from urllib.parse import quote

from .export import export_pack, open_pack
from .iiif_presentation import check_http_uri, exhibition_painting, write_presentation_manifest
from .outputs import (check_output, owned_by, refuse_protected, remove_stale_temps, replace_dir,
                      signals_interrupt, temp_dir, write_mark)

__all__ = ["write_exhibition_iiif", "MANIFEST_NAME"]

MANIFEST_NAME = "manifest.json"
COMMAND = "exhibit-iiif"


def _folder_name(name: str, used: set[str]) -> str:
    """A file-system and URL-safe folder for a painting: its pack name with anything but
    letters, digits, '-', '_' and '.' as '_', unique among `used`."""
    base = re.sub(r"[^A-Za-z0-9._-]", "_", name).strip(".") or "painting"
    folder, k = base, 1
    while folder.lower() in used or folder.lower() == MANIFEST_NAME:
        k += 1
        folder = f"{base}-{k}"
    used.add(folder.lower())
    return folder


def write_exhibition_iiif(pack_path, paintings, out, base_url: str, *, label: str,
                          summary: str = "", quality: int = 90, threads: int = 0,
                          force: bool = False, progress: bool = False,
                          language: str = "en") -> Path:
    """Exports each of `paintings` (objects with `title`, `width_cm`, `height_cm`, the
    optional metadata of gigascroll.exhibit's Painting, and `pack_name` or `name`: its
    painting in the pack at `pack_path`) as IIIF tiles into OUT/<painting>/ with the id
    BASE/<painting>, and writes OUT/manifest.json (id BASE/manifest.json, label `label`).
    Returns the manifest's path. ValueError for a bad base URL, rights URI or a painting the
    pack lacks; OSError when OUT exists (without `force`, or not made by this function)."""
    base_url = check_http_uri(base_url, "the exhibition's IIIF base URL")
    paintings = list(paintings)
    if not paintings:
        raise ValueError("an exhibition's IIIF export needs at least one painting")
    pack = open_pack(pack_path)
    names = [p.name for p in pack.paintings]
    used: set[str] = set()
    plan = []
    for p in paintings:
        name = getattr(p, "pack_name", None) or getattr(p, "name", None)
        if name not in names:
            raise ValueError(f"painting '{getattr(p, 'title', name)}': the pack holds no "
                             f"painting '{name}' (it has {', '.join(names[:10])})")
        folder = _folder_name(name, used)
        plan.append((p, name, folder, f"{base_url}/{quote(folder)}"))
    out = refuse_protected(out)
    owned = owned_by(COMMAND)
    check_output(out, force=force, directory=True, owned=owned,
                 what="an exhibition's IIIF export of gigascroll")
    with signals_interrupt():
        remove_stale_temps(out, COMMAND)
        tmp = temp_dir(out, command=COMMAND)
        try:
            entries = []
            for p, name, folder, service in plan:
                export_pack(pack_path, tmp / folder, "iiif", painting=name, quality=quality,
                            threads=threads, progress=progress, service_id=service)
                entries.append(exhibition_painting(p, service, info=tmp / folder / "info.json"))
            write_presentation_manifest(tmp / MANIFEST_NAME, entries,
                                        f"{base_url}/{MANIFEST_NAME}", label, summary=summary,
                                        language=language)
            write_mark(tmp, COMMAND)  # last: the output is whole
            replace_dir(tmp, out, owned)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    return out / MANIFEST_NAME

"""Exporting a painting of a tile pack to the museum formats, streamed from the pack's
tiles (borders cropped; the source image is not read again):

- ``iiif``: IIIF Image API 3.0 level-0 static tiles, ``OUT/info.json`` and
  ``OUT/{x},{y},{w},{h}/{w'},{h'}/0/default.jpg``, one tile per pack tile (tile width = the
  pack's payload, one scale factor per mip level), plus the full images of the small sizes
  that info.json lists;
- ``dzi``: Deep Zoom, ``OUT.dzi`` and ``OUT_files/<level>/<col>_<row>.jpg`` (tile size = the
  payload, overlap = the pack's border), levels down to 1 x 1 (those below the pack's last
  mip level are 2 x 2 means of the level above);
- ``tiff``: a tiled pyramidal BigTIFF (one IFD per mip level, JPEG or deflate).

Either reader serves: the core's ``TilePack`` or the pure-Python ``PurePack``. Outputs are
written under a temporary name and renamed into place when complete (gigascroll.outputs'
rules: an existing directory is replaced only when an export made it, as its mark says)."""

from __future__ import annotations

import json
import math
import os
import shutil
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Iterator

import numpy as np

from .outputs import (MARK, atomic_file, check_output, encode_image, owned_by,
                      refuse_input, refuse_protected, remove_stale_temps, replace_dir, signals_deferred,
                      signals_interrupt, temp_dir, write_bytes, write_mark, write_text)

__all__ = ["export_pack", "FORMATS", "open_pack", "level_bands"]

FORMATS = ("iiif", "dzi", "tiff")
# The default IIIF id: where `python -m http.server 8000` run in the output's parent serves
# the output (the Image API requires an absolute id; a bare name resolves nowhere).
DEFAULT_IIIF_PORT = 8000


def default_base_url(out) -> str:
    """http://localhost:8000/NAME, NAME the output directory's name (percent-encoded)."""
    from urllib.parse import quote
    return f"http://localhost:{DEFAULT_IIIF_PORT}/{quote(Path(out).resolve().name)}"
IIIF_CONTEXT = "http://iiif.io/api/image/3/context.json"
TIFF_TILE = 256


def open_pack(path, reader: str = "core"):
    """The pack opened with the core's reader ("core") or the pure-Python one ("python")."""
    if reader == "core":
        from ._core import TilePack
        return TilePack(path)
    if reader == "python":
        from .pack.reader import PurePack
        return PurePack(path)
    raise ValueError(f"unknown reader '{reader}' (expected core or python)")


def _painting_index(pack, painting: str | int | None) -> int:
    names = [p.name for p in pack.paintings]
    if painting is None:
        return 0
    if isinstance(painting, int) or (isinstance(painting, str) and painting.isdigit()
                                     and painting not in names):
        i = int(painting)
        if 0 <= i < len(names):
            return i
    elif painting in names:
        return names.index(painting)
    raise ValueError(f"no painting '{painting}' in the pack (it has: {', '.join(names)})")


def _crop(pack, tile: np.ndarray, level_size, tx: int, ty: int, overlap: int = 0) -> np.ndarray:
    """The payload of a tile (plus up to `overlap` texels of border where the level has
    texels there)."""
    b, P = pack.border, pack.payload
    w, h = level_size
    x0, y0 = tx * P, ty * P
    left, top = min(overlap, x0), min(overlap, y0)
    right = max(0, min(overlap, w - x0 - P))
    bottom = max(0, min(overlap, h - y0 - P))
    pw, ph = min(P, w - x0), min(P, h - y0)
    return tile[b - top:b + ph + bottom, b - left:b + pw + right]


def level_bands(pack, p: int, level: int, pool=None) -> Iterator[tuple[int, np.ndarray]]:
    """(y0, rows) for each tile row of a level: its payload rows, whole width."""
    w, h = pack.paintings[p].level_sizes[level]
    nx, ny = pack.paintings[p].level_tiles[level]
    P = pack.payload
    for ty in range(ny):
        ph = min(P, h - ty * P)
        band = np.empty((ph, w, 3), np.uint8)
        tiles = (pool.map if pool else map)(lambda tx: pack.read_tile(p, level, tx, ty), range(nx))
        for tx, t in enumerate(tiles):
            c = _crop(pack, t, (w, h), tx, ty)
            band[:, tx * P:tx * P + c.shape[1]] = c
        yield ty * P, band


def _jpeg(path: Path, pixels: np.ndarray, quality: int) -> None:
    # 4:4:4 (no chroma subsampling): paintings' fine colour detail is what they are viewed for.
    write_bytes(path, encode_image(pixels, "JPEG", quality))


def _halve(img: np.ndarray) -> np.ndarray:
    """2 x 2 means of the texels present (ceil sizes), rounded: the next smaller level."""
    h, w = img.shape[:2]
    rows, cols = np.arange(0, h, 2), np.arange(0, w, 2)
    s = np.add.reduceat(np.add.reduceat(img.astype(np.float64), rows, 0), cols, 1)
    n = (np.minimum(rows + 2, h) - rows)[:, None, None] * (np.minimum(cols + 2, w) - cols)[None, :, None]
    return np.rint(s / n).astype(np.uint8)


def _read_level(pack, p: int, level: int) -> np.ndarray:
    w, h = pack.paintings[p].level_sizes[level]
    out = np.empty((h, w, 3), np.uint8)
    for y0, band in level_bands(pack, p, level):
        out[y0:y0 + band.shape[0]] = band
    return out


class _Progress:
    def __init__(self, enabled: bool, total: int, desc: str):
        self.bar = None
        if enabled:
            from tqdm import tqdm
            self.bar = tqdm(total=total, unit="tile", desc=desc)

    def update(self, n: int = 1) -> None:
        if self.bar is not None:
            self.bar.update(n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _tile_jobs(pack, p: int):
    for level, (nx, ny) in enumerate(pack.paintings[p].level_tiles):
        for ty in range(ny):
            for tx in range(nx):
                yield level, tx, ty


def _run_tiles(pack, p: int, pool, progress, write_one) -> None:
    """write_one(level, tx, ty, tile) for every stored tile, on the pool, bounded in flight."""
    pending = []
    for job in _tile_jobs(pack, p):
        pending.append(pool.submit(lambda j: write_one(*j, pack.read_tile(p, *j)), job))
        if len(pending) >= 256:
            for f in pending[:128]:
                f.result()
                progress.update()
            pending = pending[128:]
    for f in pending:
        f.result()
        progress.update()


def _export_iiif(pack, p: int, tmp: Path, quality: int, pool, progress, service_id: str) -> None:
    pp = pack.paintings[p]
    W, H = pp.width, pp.height
    P = pack.payload

    def write_one(level, tx, ty, tile):
        s = 1 << level
        x, y = tx * P * s, ty * P * s
        rw, rh = min(P * s, W - x), min(P * s, H - y)
        c = _crop(pack, tile, pp.level_sizes[level], tx, ty)
        assert c.shape[:2] == (-(-rh // s), -(-rw // s))
        d = tmp / f"{x},{y},{rw},{rh}" / f"{c.shape[1]},{c.shape[0]}" / "0"
        d.mkdir(parents=True, exist_ok=True)
        _jpeg(d / "default.jpg", c, quality)

    _run_tiles(pack, p, pool, progress, write_one)
    # Full images of the sizes listed in info.json (the levels of at most 1024 x 1024).
    sizes = []
    for level in range(pp.levels - 1, -1, -1):
        w, h = pp.level_sizes[level]
        if max(w, h) > 1024 and sizes:
            break
        d = tmp / "full" / f"{w},{h}" / "0"
        d.mkdir(parents=True, exist_ok=True)
        _jpeg(d / "default.jpg", _read_level(pack, p, level), quality)
        sizes.append({"width": w, "height": h})
        if level == 0:
            (tmp / "full" / "max" / "0").mkdir(parents=True, exist_ok=True)
            write_bytes(tmp / "full" / "max" / "0" / "default.jpg", (d / "default.jpg").read_bytes())
    info = {"@context": IIIF_CONTEXT, "id": service_id, "type": "ImageService3",
            "protocol": "http://iiif.io/api/image", "profile": "level0",
            "width": W, "height": H, "sizes": sizes,
            "tiles": [{"width": P, "height": P, "scaleFactors": [1 << l for l in range(pp.levels)]}]}
    write_text(tmp / "info.json", json.dumps(info, indent=2) + "\n")


def _export_dzi(pack, p: int, tmp: Path, name: str, quality: int, pool, progress) -> None:
    pp = pack.paintings[p]
    W, H = pp.width, pp.height
    P, overlap = pack.payload, pack.border
    top = math.ceil(math.log2(max(W, H))) if max(W, H) > 1 else 0
    files = tmp / f"{name}_files"

    def write_one(level, tx, ty, tile):
        d = files / str(top - level)
        d.mkdir(parents=True, exist_ok=True)
        _jpeg(d / f"{tx}_{ty}.jpg", _crop(pack, tile, pp.level_sizes[level], tx, ty, overlap), quality)

    _run_tiles(pack, p, pool, progress, write_one)
    img = _read_level(pack, p, pp.levels - 1)  # fits in one tile: the smaller levels from it
    for dz in range(top - pp.levels, -1, -1):
        img = _halve(img)
        (files / str(dz)).mkdir(parents=True, exist_ok=True)
        _jpeg(files / str(dz) / "0_0.jpg", img, quality)
    write_text(tmp / f"{name}.dzi",
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Image xmlns="http://schemas.microsoft.com/deepzoom/2008" '
        f'TileSize="{P}" Overlap="{overlap}" Format="jpg">\n'
        f'  <Size Width="{W}" Height="{H}"/>\n</Image>\n')


def _tiff_tiles(pack, p: int, level: int, pool, progress) -> Iterator[np.ndarray]:
    """The level's TIFF tiles (TIFF_TILE square, row-major), cut from its tile rows: one row
    of TIFF tiles in memory at a time."""
    T = TIFF_TILE
    w, h = pack.paintings[p].level_sizes[level]
    buf = np.empty((T, w + (-w % T), 3), np.uint8)
    filled, y_out = 0, 0
    for _, band in level_bands(pack, p, level, pool):
        k = 0
        while k < band.shape[0]:
            n = min(T - filled, band.shape[0] - k)
            buf[filled:filled + n, :w] = band[k:k + n]
            buf[filled:filled + n, w:] = band[k:k + n, w - 1:w]  # edge texels repeated:
            filled, k = filled + n, k + n                        # no JPEG ringing at the edge
            if filled == T or y_out + filled == h:
                buf[filled:] = buf[filled - 1:filled]
                for x in range(0, buf.shape[1], T):
                    yield buf[:, x:x + T].copy()  # the writer may keep it past the next row
                y_out, filled = y_out + filled, 0
        progress.update(pack.paintings[p].level_tiles[level][0])


def _export_tiff(pack, p: int, tmp_file: Path, quality: int, compression: str, pool,
                 progress) -> None:
    import tifffile
    pp = pack.paintings[p]
    codec = ("jpeg", {"level": int(quality)}) if compression == "jpeg" else ("zlib", {"level": 6})
    with tifffile.TiffWriter(tmp_file, bigtiff=True) as tif:
        for level in range(pp.levels):
            w, h = pp.level_sizes[level]
            tif.write(_tiff_tiles(pack, p, level, pool, progress), shape=(h, w, 3), dtype=np.uint8,
                      tile=(TIFF_TILE, TIFF_TILE), photometric="rgb", compression=codec[0],
                      compressionargs=codec[1], subfiletype=0 if level == 0 else 1,
                      metadata=None, maxworkers=1,
                      **({"subsampling": (1, 1)} if compression == "jpeg" else {}))  # 4:4:4


def export_pack(pack_path, out, fmt: str, *, painting=None, quality: int = 90,
                compression: str = "jpeg", force: bool = False, reader: str = "core",
                threads: int = 0, progress: bool = False, service_id: str | None = None) -> Path:
    """Exports one painting of the pack at `pack_path` to `out` in format `fmt` (iiif, dzi,
    tiff; see the module doc) and returns the path written (for dzi, the .dzi file).
    `service_id` (iiif): the absolute http(s) URI the export is served at, info.json's id
    (default: default_base_url(out)).
    ValueError for a bad format, quality, compression or painting; OSError when the output
    exists (without force) or cannot be written."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown export format '{fmt}' (expected iiif, dzi or tiff)")
    if not (isinstance(quality, (int, np.integer)) and 1 <= quality <= 100):
        raise ValueError(f"quality must be an integer in [1, 100], got {quality}")
    if compression not in ("jpeg", "deflate"):
        raise ValueError(f"unknown compression '{compression}' (expected jpeg or deflate)")
    if fmt == "iiif":
        from .iiif_presentation import check_http_uri
        service_id = check_http_uri(service_id or default_base_url(out), "service_id")
    elif service_id is not None:
        raise ValueError("service_id (--base-url) applies to the iiif format only")
    pack = open_pack(pack_path, reader)
    p = _painting_index(pack, painting)
    out = refuse_protected(out)
    if fmt == "dzi" and out.suffix == ".dzi":
        out = out.with_suffix("")
    final = [out.with_name(out.name + ".dzi"), out.with_name(out.name + "_files")] if fmt == "dzi" else [out]
    owned = owned_by("export", format=fmt)
    folder = {"iiif": out, "dzi": final[-1], "tiff": None}[fmt]
    for f in final:  # the shared rules: a directory only if an export made it
        refuse_input(f, pack_path, "the pack being exported")
        check_output(f, force=force, directory=f == folder, owned=owned,
                     what=f"an export ({fmt}) of gigascroll")
    if not out.parent.is_dir():
        raise OSError(f"{out.parent}: no such directory")
    if not os.access(out.parent, os.W_OK):
        raise OSError(f"{out.parent}: not writable")
    pp = pack.paintings[p]
    with signals_interrupt():  # SIGTERM / SIGHUP: the temporaries go as for Ctrl-C
        if fmt == "tiff":
            with atomic_file(out, durable=True) as tmp:
                _with_pool(threads, progress, pp, fmt, lambda pool, bar: _export_tiff(
                    pack, p, tmp, quality, compression, pool, bar))
            return out
        remove_stale_temps(out, "export", format=fmt)  # of runs killed outright
        tmp = temp_dir(out, command="export", format=fmt)
        try:
            if fmt == "iiif":
                _with_pool(threads, progress, pp, fmt, lambda pool, bar: _export_iiif(
                    pack, p, tmp, quality, pool, bar, service_id))
                write_mark(tmp, "export", format=fmt)  # last: the output is whole
                replace_dir(tmp, out, owned)
            else:  # the tiles first, the .dzi (which marks it complete) last
                _with_pool(threads, progress, pp, fmt, lambda pool, bar: _export_dzi(
                    pack, p, tmp, out.name, quality, pool, bar))
                write_mark(tmp / final[1].name, "export", format=fmt)
                with signals_deferred():  # the tiles and their .dzi: both or neither
                    replace_dir(tmp / final[1].name, final[1], owned)
                    os.replace(tmp / final[0].name, final[0])
                (tmp / MARK).unlink()
                tmp.rmdir()
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    return final[0]


def _with_pool(threads: int, progress: bool, pp, fmt: str, work) -> None:
    """work(pool, bar) on a thread pool whose queued jobs are cancelled when it fails (so the
    cleanup after an error or a signal does not wait for them)."""
    bar = _Progress(progress, sum(nx * ny for nx, ny in pp.level_tiles), f"export {fmt}")
    pool = ThreadPoolExecutor(threads or os.cpu_count() or 1)
    try:
        work(pool, bar)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        bar.close()

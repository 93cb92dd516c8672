"""Building tile packs: the merged page-table layout and the streamed build of one pack
from images (format in README.md and the core's pack/format.h). A build goes into a
temporary sibling directory renamed into place at the end."""

from __future__ import annotations

import json
import os
import queue
import shutil
import threading
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from .. import _core
from .._core import TilePack, painting_geometry
from .colour import plan_colour
from .images import ImageSource, open_image

__all__ = ["build_pack", "plan_layout", "MANIFEST"]

MANIFEST = "manifest.json"


# ----------------------------------------------------------------------------- layout

def plan_layout(table_sizes: Sequence[tuple[int, int]], method: str = "brkga", seed: int = 0):
    """Places the paintings' power-of-two page tables (Mp, Np) in one merged power-of-two
    table, each at offsets that are multiples of its own size (so eqs 5, 6 stay exact).
    Returns (table_width, table_height, offsets, info); info holds both packers' fill ratios
    (BRKGA and the shelf baseline), whichever `method` was chosen."""
    if method not in ("brkga", "shelf"):
        raise ValueError(f"unknown layout method '{method}' (expected brkga or shelf)")
    return _core.layout_page_tables([(int(w), int(h)) for w, h in table_sizes], method, seed)


# ----------------------------------------------------------------------------- building

def _prefetch(it: Iterator[np.ndarray]) -> Iterator[np.ndarray]:
    """Runs the band reader one band ahead on a helper thread (OpenImageIO releases the GIL
    while decoding), so reading overlaps the C++ reduction and tile cutting. At most two
    bands are alive at once (the one being packed and the one being read): peak memory."""
    q: queue.Queue = queue.Queue()
    slots = threading.Semaphore(2)
    stop = threading.Event()
    done = object()

    def worker():
        try:
            while True:
                while not slots.acquire(timeout=0.1):
                    if stop.is_set():
                        return
                if stop.is_set():
                    return
                band = next(it, done)
                q.put(band)
                if band is done:
                    return
        except BaseException as e:  # handed to the consumer
            q.put(e)

    t = threading.Thread(target=worker, name="gigascroll-band-reader", daemon=True)
    t.start()
    try:
        while True:
            item = q.get()
            if item is done:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
            del item
            slots.release()  # the consumer is done with this band
    finally:
        stop.set()
        t.join()


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


# The files a pack directory holds: --force replaces a directory only if it holds nothing else
# and its manifest says it is a pack (a source tree with a manifest.json is not one).
PACK_FILES = frozenset({MANIFEST, "tiles.bin", "index.bin"})


def _is_pack_dir(path: Path) -> bool:
    names = {p.name for p in path.iterdir()}
    manifest = path / MANIFEST
    if not names <= PACK_FILES or not manifest.is_file() or manifest.is_symlink():
        return False
    try:
        m = json.loads(manifest.read_text())
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return False
    return isinstance(m, dict) and m.get("format") == "gigascroll-pack"


def _prepare_output(out: Path, force: bool) -> None:
    if out.exists() or out.is_symlink():
        if not force:
            raise OSError(f"{out}: already exists (use --force / force=True to overwrite)")
        if out.is_dir() and not out.is_symlink():
            if any(out.iterdir()) and not _is_pack_dir(out):
                raise OSError(f"{out}: exists and is not a tile pack; refusing to overwrite it")
        else:
            raise OSError(f"{out}: exists and is not a directory; refusing to overwrite it")


def build_pack(inputs, out, tile_size: int = 128, border: int = 4, codec: str = "raw", *,
               force: bool = False, names: Sequence[str] | None = None, layout: str = "brkga",
               seed: int = 0, threads: int = 0, zstd_level: int = 3, bc1_fit: str = "range",
               progress: bool = False,
               band_rows: int = 0, colour: str = "convert", intent: str = "relative",
               black_point_compensation: bool = True) -> TilePack:
    """Builds a tile pack at `out` from one image or a list of images (file paths or numpy
    arrays, one painting each) and returns it opened. The build goes into a temporary sibling
    directory renamed into place at the end, so a failed or interrupted build leaves nothing
    that opens as a pack. Colours (see .colour): `colour="convert"` turns an embedded ICC
    profile (or EXR chromaticities) into sRGB with the rendering `intent`; "keep" stores the
    values untouched; either way the manifest records what was done. `codec="bc1"` stores
    DXT1 blocks (libsquish's `bc1_fit`: "range", fast, or "cluster", ~1.4 dB better at ~25x
    the encoding time), which the cache keeps compressed."""
    if isinstance(inputs, (str, os.PathLike, np.ndarray)):
        inputs = [inputs]
    inputs = list(inputs)
    if not inputs:
        raise ValueError("no input images")
    if codec not in ("raw", "zstd", "bc1"):
        raise ValueError(f"unknown codec '{codec}' (expected raw, zstd or bc1)")
    if not (isinstance(tile_size, (int, np.integer)) and isinstance(border, (int, np.integer))):
        raise ValueError("tile_size and border must be integers")
    if border < 0 or tile_size <= 2 * border:
        raise ValueError(f"tile_size ({tile_size}) must be larger than 2 * border ({2 * border})")
    if bc1_fit not in ("range", "cluster"):
        raise ValueError(f"bc1_fit must be 'range' or 'cluster', got '{bc1_fit}'")
    if codec == "bc1" and (tile_size % 4 or (tile_size - 2 * border) % 4):
        raise ValueError(f"bc1 needs tile_size and payload (tile_size - 2 border) to be multiples "
                         f"of 4, got {tile_size} and {tile_size - 2 * border}")
    if names is not None and len(names) != len(inputs):
        raise ValueError("names must have one entry per input")
    out = Path(out)
    colour_options = {"mode": colour, "intent": intent,
                      "black_point_compensation": black_point_compensation}
    plan_colour("build_pack", 3, **colour_options)  # unknown mode / intent: now
    _prepare_output(out, force)

    sources: list[ImageSource] = []
    bar = None
    tmp = out.parent / f"{out.name}.tmp-{os.getpid()}"
    try:
        for i, image in enumerate(inputs):
            name = names[i] if names else (None if not isinstance(image, np.ndarray) else
                                           f"painting{i}" if len(inputs) > 1 else "painting")
            sources.append(open_image(image, name, band_rows, colour_options))
        used = set()
        for s in sources:  # unique names
            base, k = s.name, 1
            while s.name in used:
                k += 1
                s.name = f"{base}-{k}"
            used.add(s.name)
        geoms = [painting_geometry(s.width, s.height, tile_size, border) for s in sources]
        table_w, table_h, offsets, info = plan_layout([g["table_size"] for g in geoms], layout, seed)

        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir(parents=True)
        builder = _core.PackBuilder(tmp, tile_size, border, codec, zstd_level, threads, bc1_fit)
        total = sum(s.width * s.height for s in sources)
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=total / 1e6, unit="Mpx", unit_scale=False, desc="pack",
                       bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} Mpx [{elapsed}<{remaining},"
                                  " {rate_fmt}]")
        for s, (ox, oy) in zip(sources, offsets):
            builder.begin_painting(s.name, s.width, s.height, s.source, s.conversion, ox, oy,
                                   "" if s.colour is None else json.dumps(s.colour))
            bands = _prefetch(s.bands())
            try:
                for band in bands:
                    builder.add_rows(band)
                    if bar is not None:
                        bar.update(band.shape[0] * band.shape[1] / 1e6)
            finally:
                bands.close()  # joins the reader thread before the image is closed
            builder.end_painting()
            s.close()
        builder.finish(table_w, table_h, json.dumps(info))
        del builder
        if bar is not None:
            bar.close()
        if out.exists():
            shutil.rmtree(out)
        os.rename(tmp, out)
        _fsync_dir(out.parent)  # make the rename itself durable
    except BaseException:
        if bar is not None:
            bar.close()
        for s in sources:
            s.close()
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return TilePack(out)

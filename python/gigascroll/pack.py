"""Tile packs: reading images in bands, building packs, and opening them.

A pack is a directory (format described in README.md and cpp/vt/pack_format.h) built by
:func:`build_pack` and read by :class:`TilePack`. Images are read through OpenImageIO in
bands of rows, converted to 8-bit RGB and streamed into the C++ builder, so peak memory grows
with the image width, not its area.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from . import _core
from ._core import PackPainting, TilePack, painting_geometry, render_ink_landscape

__all__ = ["TilePack", "PackPainting", "build_pack", "open_image", "painting_geometry",
           "to_rgb8", "plan_layout", "synth_painting", "render_ink_landscape", "read_level",
           "pack_summary", "pack_manifest", "verify_pack"]

MANIFEST = "manifest.json"


# ----------------------------------------------------------------------------- conversion

def _srgb_encode(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] -> sRGB-encoded [0, 1] (IEC 61966-2-1)."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def describe_conversion(dtype: np.dtype, channels: int, stored_type: str | None = None) -> str:
    """How an input of this dtype and channel count becomes 8-bit RGB (for the manifest).
    `stored_type` names the file's own pixel type when it differs from `dtype` (the type the
    reader asked OpenImageIO for, e.g. half -> float32, int16 -> uint16)."""
    steps = []
    dtype = np.dtype(dtype)
    source = f"{stored_type} read as {dtype.name}; " if stored_type and stored_type != dtype.name else ""
    if dtype == np.uint8:
        pass
    elif dtype == np.uint16:
        steps.append("uint16 -> uint8 (v / 257, rounded)")
    elif dtype.kind == "f":
        steps.append(f"{dtype.name} linear -> clamped to [0, 1], sRGB-encoded, uint8 (rounded)")
    else:
        raise ValueError(f"unsupported pixel type {dtype.name} (expected uint8, uint16 or float)")
    if channels in (1, 2):
        steps.append("grey -> RGB (replicated)")
    if channels in (2, 4):
        steps.append("alpha dropped")
    if channels > 4:
        steps.append(f"channels 3..{channels - 1} dropped")
    if not steps:
        return source + "none (8-bit RGB)" if source else "none (8-bit RGB)"
    return source + "; ".join(steps)


def to_rgb8(pixels: np.ndarray) -> np.ndarray:
    """Converts an (h, w), (h, w, c) uint8/uint16/float image band to C-contiguous (h, w, 3)
    uint8: grey replicated, alpha and extra channels dropped, 16-bit scaled by 1/257, float
    clamped to [0, 1] and sRGB-encoded. ValueError for NaN or unsupported types."""
    a = np.asarray(pixels)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] < 1:
        raise ValueError(f"expected an (h, w) or (h, w, channels) image, got shape {a.shape}")
    c = a.shape[2]
    a = a[:, :, :1] if c <= 2 else a[:, :, :3]
    if a.dtype == np.uint8:
        out = a
    elif a.dtype == np.uint16:
        out = ((a.astype(np.uint32) * 2 + 257) // 514).astype(np.uint8)  # round(v / 257)
    elif a.dtype.kind == "f":
        if np.isnan(a).any():
            raise ValueError("image contains NaN pixels")
        out = np.rint(_srgb_encode(a.astype(np.float64)) * 255.0).astype(np.uint8)
    else:
        raise ValueError(f"unsupported pixel type {a.dtype.name} (expected uint8, uint16 or float)")
    if out.shape[2] == 1:
        out = np.repeat(out, 3, axis=2)
    return np.ascontiguousarray(out)


# ----------------------------------------------------------------------------- image sources

@dataclass
class ImageSource:
    """An image read in bands of rows: width, height, the manifest's name/source/conversion."""
    name: str
    source: str
    width: int
    height: int
    conversion: str
    band_rows: int

    def bands(self) -> Iterator[np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError

    def close(self) -> None:
        pass


class ArraySource(ImageSource):
    def __init__(self, array: np.ndarray, name: str, band_rows: int = 256):
        a = np.asarray(array)
        if a.ndim not in (2, 3) or a.shape[0] == 0 or a.shape[1] == 0 or (a.ndim == 3 and a.shape[2] == 0):
            raise ValueError(f"image '{name}' is empty or not an image (shape {a.shape})")
        channels = 1 if a.ndim == 2 else a.shape[2]
        super().__init__(name, "array", a.shape[1], a.shape[0],
                         describe_conversion(a.dtype, channels), band_rows)
        self._array = a

    def bands(self) -> Iterator[np.ndarray]:
        for y in range(0, self.height, self.band_rows):
            yield to_rgb8(self._array[y:y + self.band_rows])


class FileSource(ImageSource):
    """An image file read through OpenImageIO, in bands aligned to its tile rows if tiled."""

    def __init__(self, path: str | os.PathLike, name: str | None = None, band_rows: int = 0):
        import OpenImageIO as oiio
        self._oiio = oiio
        path = Path(path)
        if not path.is_file():
            raise OSError(f"{path}: no such image file")
        # Keep colours as stored (no alpha premultiplication): alpha is dropped anyway.
        config = oiio.ImageSpec()
        config.attribute("oiio:UnassociatedAlpha", 1)
        inp = oiio.ImageInput.open(str(path), config)
        if inp is None:
            raise OSError(f"{path}: cannot read image: {oiio.geterror() or 'unknown format'}")
        spec = inp.spec()
        if spec.width <= 0 or spec.height <= 0 or spec.nchannels <= 0:
            inp.close()
            raise ValueError(f"{path}: image is empty ({spec.width} x {spec.height})")
        if spec.depth > 1:
            inp.close()
            raise ValueError(f"{path}: volume images are not supported")
        basetype = spec.format.basetype
        if basetype == oiio.UINT8:
            self._format, dtype = oiio.UINT8, np.uint8
        elif basetype in (oiio.HALF, oiio.FLOAT, oiio.DOUBLE):
            self._format, dtype = oiio.FLOAT, np.float32
        else:  # 16-bit and other integer types: OpenImageIO rescales to uint16
            self._format, dtype = oiio.UINT16, np.uint16
        if spec.tile_width > 0:
            band_rows = spec.tile_height * max(1, -(-max(band_rows, 128) // spec.tile_height))
        elif band_rows <= 0:
            band_rows = 128
        self._nch = min(spec.nchannels, 4)
        super().__init__(name or path.stem, str(path), spec.width, spec.height,
                         describe_conversion(dtype, spec.nchannels, str(spec.format)), band_rows)
        self._inp = inp
        self._spec = spec

    def bands(self) -> Iterator[np.ndarray]:
        spec = self._spec
        for y in range(0, self.height, self.band_rows):
            y1 = min(self.height, y + self.band_rows)
            if spec.tile_width > 0:  # tiled: whole tile rows (band_rows is a multiple)
                data = self._inp.read_tiles(0, 0, spec.x, spec.x + self.width, spec.y + y,
                                            spec.y + y1, spec.z, spec.z + 1, 0, self._nch,
                                            self._format)
            else:
                data = self._inp.read_scanlines(0, 0, spec.y + y, spec.y + y1, spec.z, 0,
                                                self._nch, self._format)
            if data is None or (hasattr(data, "size") and data.size == 0):
                raise OSError(f"{self.source}: corrupt or truncated image near row {y}: "
                              f"{self._inp.geterror() or 'read failed'}")
            data = np.asarray(data).reshape(y1 - y, self.width, self._nch)
            yield to_rgb8(data)

    def close(self) -> None:
        if self._inp is not None:
            self._inp.close()
            self._inp = None


def open_image(image, name: str | None = None, band_rows: int = 0) -> ImageSource:
    """An ImageSource for a numpy array or an image file path."""
    if isinstance(image, ImageSource):
        return image
    if isinstance(image, np.ndarray):
        return ArraySource(image, name or "painting", band_rows or 256)
    if isinstance(image, (str, os.PathLike)):
        return FileSource(image, name, band_rows)
    raise ValueError(f"cannot read an image from {type(image).__name__}")


# ----------------------------------------------------------------------------- built-in painting

def synth_painting(path, width: int, height: int, seed: int = 0, tile: int = 256,
                   compression: str = "none", progress: bool = False) -> Path:
    """Writes the built-in ink landscape (width x height, deterministic for a seed) as a tiled
    BigTIFF, band by band (one tile row at a time), never holding the whole image. The file is
    written under a temporary name and renamed when complete."""
    import OpenImageIO as oiio
    width, height, tile = int(width), int(height), int(tile)
    if width <= 0 or height <= 0:
        raise ValueError(f"painting size must be positive, got {width} x {height}")
    if width > (1 << 30) or height > (1 << 30):
        raise ValueError("painting is too large")
    if tile <= 0 or tile % 16:
        raise ValueError("TIFF tile size must be a positive multiple of 16")
    path = Path(path)
    tmp = path.with_name(f"{path.name}.tmp-{os.getpid()}{path.suffix}")
    spec = oiio.ImageSpec(width, height, 3, oiio.UINT8)
    spec.tile_width = spec.tile_height = tile
    spec.attribute("tiff:bigtiff", 1)
    spec.attribute("compression", compression)
    spec.attribute("Software", "gigascroll synth")
    spec.attribute("ImageDescription", f"gigascroll ink landscape, seed {seed}")
    out = oiio.ImageOutput.create(str(tmp))
    if out is None or not out.open(str(tmp), spec):
        raise OSError(f"{path}: cannot write: {oiio.geterror()}")
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=height, unit="row", desc="synth")
    try:
        for y in range(0, height, tile):
            rows = min(tile, height - y)
            band = render_ink_landscape(width, height, y, rows, seed)
            if not out.write_tiles(0, width, y, y + rows, 0, 1, band):
                raise OSError(f"{path}: write failed: {out.geterror()}")
            if bar is not None:
                bar.update(rows)
        if not out.close():
            raise OSError(f"{path}: write failed: {out.geterror()}")
        os.replace(tmp, path)
    except BaseException:
        out.close()
        tmp.unlink(missing_ok=True)
        raise
    finally:
        if bar is not None:
            bar.close()
    return path


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


def _prepare_output(out: Path, force: bool) -> None:
    if out.exists() or out.is_symlink():
        if not force:
            raise OSError(f"{out}: already exists (use --force / force=True to overwrite)")
        if out.is_dir() and not out.is_symlink():
            if any(out.iterdir()) and not (out / MANIFEST).exists():
                raise OSError(f"{out}: exists and is not a tile pack; refusing to overwrite it")
        else:
            raise OSError(f"{out}: exists and is not a directory; refusing to overwrite it")


def build_pack(inputs, out, tile_size: int = 128, border: int = 4, codec: str = "raw", *,
               force: bool = False, names: Sequence[str] | None = None, layout: str = "brkga",
               seed: int = 0, threads: int = 0, zstd_level: int = 3, progress: bool = False,
               band_rows: int = 0) -> TilePack:
    """Builds a tile pack at `out` from one image or a list of images (file paths or numpy
    arrays, one painting each) and returns it opened. The build goes into a temporary sibling
    directory renamed into place at the end, so a failed or interrupted build leaves nothing
    that opens as a pack."""
    if isinstance(inputs, (str, os.PathLike, np.ndarray)):
        inputs = [inputs]
    inputs = list(inputs)
    if not inputs:
        raise ValueError("no input images")
    if codec not in ("raw", "zstd"):
        raise ValueError(f"unknown codec '{codec}' (expected raw or zstd)")
    if not (isinstance(tile_size, (int, np.integer)) and isinstance(border, (int, np.integer))):
        raise ValueError("tile_size and border must be integers")
    if border < 0 or tile_size <= 2 * border:
        raise ValueError(f"tile_size ({tile_size}) must be larger than 2 * border ({2 * border})")
    if names is not None and len(names) != len(inputs):
        raise ValueError("names must have one entry per input")
    out = Path(out)
    _prepare_output(out, force)

    sources: list[ImageSource] = []
    bar = None
    tmp = out.parent / f"{out.name}.tmp-{os.getpid()}"
    try:
        for i, image in enumerate(inputs):
            name = names[i] if names else (None if not isinstance(image, np.ndarray) else
                                           f"painting{i}" if len(inputs) > 1 else "painting")
            sources.append(open_image(image, name, band_rows))
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
        builder = _core.PackBuilder(tmp, tile_size, border, codec, zstd_level, threads)
        total = sum(s.width * s.height for s in sources)
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=total / 1e6, unit="Mpx", unit_scale=False, desc="pack",
                       bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} Mpx [{elapsed}<{remaining},"
                                  " {rate_fmt}]")
        for s, (ox, oy) in zip(sources, offsets):
            builder.begin_painting(s.name, s.width, s.height, s.source, s.conversion, ox, oy)
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


# ----------------------------------------------------------------------------- reading helpers

def pack_manifest(path) -> dict:
    """The manifest of a pack as a dict (after checking that the pack opens)."""
    TilePack(path)
    with open(Path(path) / MANIFEST) as f:
        return json.load(f)


def read_level(pack: TilePack, painting: int, level: int) -> np.ndarray:
    """Assembles one whole mip level (height, width, 3) from the payloads of its tiles."""
    p = pack.paintings[painting]
    if not 0 <= level < p.levels:
        raise ValueError(f"level {level} out of range (painting has {p.levels})")
    w, h = p.level_sizes[level]
    nx, ny = p.level_tiles[level]
    b, P = pack.border, pack.payload
    out = np.empty((h, w, 3), np.uint8)
    for ty in range(ny):
        for tx in range(nx):
            t = pack.read_tile(painting, level, tx, ty)
            ph, pw = min(P, h - ty * P), min(P, w - tx * P)
            out[ty * P:ty * P + ph, tx * P:tx * P + pw] = t[b:b + ph, b:b + pw]
    return out


def verify_pack(pack: TilePack, progress: bool = False) -> int:
    """Reads every stored tile, verifying its checksum; returns the number of tiles read.
    Raises OSError on the first corrupt tile."""
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=pack.tile_count, unit="tile", desc="verify")
    out = np.empty((pack.tile_size, pack.tile_size, 3), np.uint8)
    n = 0
    for i, p in enumerate(pack.paintings):
        for l, (nx, ny) in enumerate(p.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    pack.read_tile_into(i, l, tx, ty, out)
                    n += 1
            if bar is not None:
                bar.update(nx * ny)
    if bar is not None:
        bar.close()
    return n


def pack_summary(pack: TilePack) -> str:
    """A human-readable summary of a pack: geometry, layout and paintings."""
    m = pack_manifest(pack.path)
    pt = m["page_table"]
    size = sum(f.stat().st_size for f in Path(pack.path).iterdir() if f.is_file())
    lines = [
        f"tile pack {pack.path}",
        f"  format {m['format']} v{m['version']}, codec {pack.codec}, tile {pack.tile_size} px "
        f"(border {pack.border}, payload {pack.payload}), {pack.tile_count} tiles, "
        f"{size / 2**20:.1f} MiB",
        f"  merged page table {pack.table_size[0]} x {pack.table_size[1]}"
        + (f", packer {pt['packer']}" if "packer" in pt else "")
        + (f", fill {pt['fill_ratio']:.3f}" if "fill_ratio" in pt else "")
        + (f" (shelf {pt['shelf_fill_ratio']:.3f}, BRKGA {pt['brkga_fill_ratio']:.3f})"
           if "shelf_fill_ratio" in pt and "brkga_fill_ratio" in pt else ""),
    ]
    for i, p in enumerate(pack.paintings):
        lines.append(
            f"  [{i}] {p.name}: {p.width} x {p.height}, {p.levels} levels, {p.tile_count} tiles, "
            f"page table {p.table_size[0]} x {p.table_size[1]} at {p.table_offset}, "
            f"uv scale ({p.uv_scale[0]:.6f}, {p.uv_scale[1]:.6f})")
        lines.append(f"      source {p.source}; conversion: {p.conversion}")
    return "\n".join(lines)

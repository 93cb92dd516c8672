"""Images read in bands of rows and converted to 8-bit RGB: numpy arrays and any file
OpenImageIO reads. Peak memory grows with the image width, not its area."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from .colour import plan_colour

__all__ = ["ImageSource", "ArraySource", "FileSource", "open_image", "to_rgb8",
           "describe_conversion"]


# ----------------------------------------------------------------------------- conversion

def _srgb_encode(linear: np.ndarray) -> np.ndarray:
    """Linear [0, 1] -> sRGB-encoded [0, 1] (IEC 61966-2-1)."""
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


# Signed sample types OpenImageIO rescales to uint16 (value 0 -> 0, the type's maximum -> 65535,
# negative values -> 0), with the type's maximum.
_SIGNED = {"int8": 127, "int16": 32767, "int32": 2147483647, "int64": 9223372036854775807}


def describe_conversion(dtype: np.dtype, channels: int, stored_type: str | None = None) -> str:
    """How an input of this dtype and channel count becomes 8-bit RGB (for the manifest).
    `stored_type` names the file's own pixel type when it differs from `dtype` (the type the
    reader asked OpenImageIO for, e.g. half -> float32, int16 -> uint16)."""
    steps = []
    dtype = np.dtype(dtype)
    source = f"{stored_type} read as {dtype.name}; " if stored_type and stored_type != dtype.name else ""
    if source and stored_type in _SIGNED and dtype == np.uint16:  # what OpenImageIO's rescale does
        source = (f"{stored_type} read as uint16 (negative values clamped to 0, [0, "
                  f"{_SIGNED[stored_type]}] scaled to [0, 65535]); ")
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
    colour: dict | None = None  # the manifest's colour record (see .colour), None: not recorded

    def bands(self) -> Iterator[np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError

    def close(self) -> None:
        pass


class ArraySource(ImageSource):
    """A numpy array: untagged, so its values are assumed sRGB (recorded as such)."""

    def __init__(self, array: np.ndarray, name: str, band_rows: int = 256, colour=None):
        a = np.asarray(array)
        if a.ndim not in (2, 3) or a.shape[0] == 0 or a.shape[1] == 0 or (a.ndim == 3 and a.shape[2] == 0):
            raise ValueError(f"image '{name}' is empty or not an image (shape {a.shape})")
        channels = 1 if a.ndim == 2 else a.shape[2]
        super().__init__(name, "array", a.shape[1], a.shape[0],
                         describe_conversion(a.dtype, channels), band_rows)
        self._array = a
        if colour is not None:
            self.colour = plan_colour(f"image '{name}'", channels, **colour).record

    def bands(self) -> Iterator[np.ndarray]:
        for y in range(0, self.height, self.band_rows):
            yield to_rgb8(self._array[y:y + self.band_rows])


def _is_cmyk(spec) -> bool:
    """Whether a file's pixels are CMYK (OpenImageIO turns them into RGB by a naive formula
    unless asked for the raw values)."""
    for name in ("tiff:ColorSpace", "jpeg:ColorSpace", "oiio:ColorModel"):
        v = spec.getattribute(name)
        if isinstance(v, str) and v.upper() == "CMYK":
            return True
    return spec.getattribute("tiff:PhotometricInterpretation") == 5  # SEPARATED (inks)


# Tiles taller than TALL_TILE_BANDS bands whose tile row would take more than TALL_TILE_BYTES
# are read one tile at a time into bands of at most BAND_BYTES (each tile decoded once per
# band it crosses) instead of whole tile rows, so memory stays a band of the image's width.
TALL_TILE_BANDS = 4
TALL_TILE_BYTES = 64 << 20
BAND_BYTES = 16 << 20


class FileSource(ImageSource):
    """An image file read through OpenImageIO, in bands aligned to its tile rows if tiled
    (tiles much taller than a band are cut into bands). CMYK files are read raw and converted
    through their CMYK profile (or the default one)."""

    def __init__(self, path: str | os.PathLike, name: str | None = None, band_rows: int = 0,
                 colour: dict | None = None):
        import OpenImageIO as oiio
        self._oiio = oiio
        self._inp = None
        path = Path(path)
        require_utf8_path(path)
        if not path.is_file():
            raise OSError(f"{path}: no such image file")
        # Keep colours as stored (no alpha premultiplication): alpha is dropped anyway.
        config = oiio.ImageSpec()
        config.attribute("oiio:UnassociatedAlpha", 1)
        inp = oiio.ImageInput.open(str(path), config)
        if inp is None:
            raise OSError(f"{path}: cannot read image: {_one_line(oiio.geterror()) or 'unknown format'}")
        spec = inp.spec()
        self._cmyk = _is_cmyk(spec)
        if self._cmyk:  # the raw inks, converted below with the CMYK profile
            inp.close()
            config.attribute("oiio:RawColor", 1)
            inp = oiio.ImageInput.open(str(path), config)
            if inp is None:
                raise OSError(f"{path}: cannot read image: {_one_line(oiio.geterror()) or 'unknown format'}")
            spec = inp.spec()
            if spec.nchannels < 4:
                inp.close()
                raise ValueError(f"{path}: CMYK image with {spec.nchannels} channels cannot be read")
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
        self._nch = min(spec.nchannels, 5 if self._cmyk else 4)
        self._tall_tiles = False
        if spec.tile_width > 0:
            rows = max(band_rows, 128)
            row_bytes = spec.width * self._nch * np.dtype(dtype).itemsize
            if spec.tile_height > TALL_TILE_BANDS * rows and spec.tile_height * row_bytes > TALL_TILE_BYTES:
                # Tiles much taller than a band: bands of up to BAND_BYTES, each tile decoded
                # once per band it crosses.
                band_rows = max(rows, min(spec.tile_height // 2, BAND_BYTES // row_bytes))
                self._tall_tiles = True
            else:
                band_rows = spec.tile_height * max(1, -(-rows // spec.tile_height))
        elif band_rows <= 0:
            band_rows = 128
        super().__init__(name or path.stem, str(path), spec.width, spec.height,
                         describe_conversion(dtype, spec.nchannels, str(spec.format)), band_rows)
        self._inp = inp
        self._spec = spec
        self._plan = None
        if colour is None and self._cmyk:
            inp.close()
            self._inp = None
            raise ValueError(f"{path}: a CMYK image needs colour conversion (colour options)")
        if colour is not None:  # colour management (see .colour): profile or chromaticities
            try:
                icc = spec.getattribute("ICCProfile")
                plan = plan_colour(str(path), spec.nchannels,
                                   None if icc is None else np.asarray(icc, np.uint8).tobytes(),
                                   spec.getattribute("chromaticities"), **colour,
                                   cmyk=self._cmyk)
            except BaseException:
                inp.close()
                self._inp = None
                raise
            self.colour = plan.record
            if plan.transforms:
                self._plan = plan
                stored = (f"{spec.format} read as {np.dtype(dtype).name}; "
                          if str(spec.format) != np.dtype(dtype).name else "")
                rest = describe_conversion(np.uint16, 1 if plan.channels == 1 else 3)
                self.conversion = stored + plan.step() + "; " + rest
                extra = spec.nchannels - plan.channels
                if extra > 0:
                    self.conversion += (f"; {'alpha' if extra == 1 else f'{extra} extra channels'}"
                                        " dropped")

    def _read(self, x0: int, x1: int, y0: int, y1: int):
        spec = self._spec
        if spec.tile_width > 0:
            return self._inp.read_tiles(0, 0, spec.x + x0, spec.x + x1, spec.y + y0, spec.y + y1,
                                        spec.z, spec.z + 1, 0, self._nch, self._format)
        return self._inp.read_scanlines(0, 0, spec.y + y0, spec.y + y1, spec.z, 0, self._nch,
                                        self._format)

    def _check(self, data, y: int) -> None:
        # A decoder that reports an error (a truncated JPEG: "Premature end of JPEG file")
        # may still return pixels (flat grey for the missing part): never store those.
        failed = data is None or (hasattr(data, "size") and data.size == 0)
        if failed or self._inp.has_error:
            raise OSError(f"{self.source}: corrupt or truncated image near row {y}: "
                          f"{_one_line(self._inp.geterror()) or 'read failed'}")

    def _tall_band(self, y: int, y1: int) -> np.ndarray:
        """Rows [y, y1) of an image whose tiles are much taller than a band: one tile at a
        time, keeping only this band's rows (memory: the band and one tile)."""
        spec = self._spec
        tw, th = spec.tile_width, spec.tile_height
        band = np.empty((y1 - y, self.width, self._nch),
                        np.float32 if self._format == self._oiio.FLOAT else
                        np.uint8 if self._format == self._oiio.UINT8 else np.uint16)
        for ty0 in range(y // th * th, y1, th):  # at most two tile rows
            ty1 = min(self.height, ty0 + th)
            r0, r1 = max(y, ty0), min(y1, ty1)
            for x in range(0, self.width, tw):
                x1 = min(self.width, x + tw)
                data = self._read(x, x1, ty0, ty1)
                self._check(data, r0)
                tile = np.asarray(data).reshape(ty1 - ty0, x1 - x, self._nch)
                band[r0 - y:r1 - y, x:x1] = tile[r0 - ty0:r1 - ty0]
                del data, tile
        return band


    def bands(self) -> Iterator[np.ndarray]:
        for y in range(0, self.height, self.band_rows):
            y1 = min(self.height, y + self.band_rows)
            if self._tall_tiles:
                data = self._tall_band(y, y1)
            else:  # tiled: whole tile rows (band_rows is a multiple)
                data = self._read(0, self.width, y, y1)
                self._check(data, y)
                data = np.asarray(data).reshape(y1 - y, self.width, self._nch)
            if self._cmyk and self._plan is None:  # pragma: no cover - refused in __init__
                raise ValueError(f"{self.source}: CMYK image without a colour transform")
            yield to_rgb8(data if self._plan is None else self._plan.apply(data))

    def close(self) -> None:
        if self._inp is not None:
            self._inp.close()
            self._inp = None


def require_utf8_path(path) -> None:
    """OSError for a path that is not valid UTF-8 (OpenImageIO, the core and manifest.json
    take UTF-8 names only): a clear message instead of a codec error half-way."""
    try:
        os.fsencode(path).decode("utf-8")
    except UnicodeDecodeError:
        shown = os.fsencode(path).decode("utf-8", "backslashreplace")
        raise OSError(f"{shown}: file name is not valid UTF-8; rename it") from None


def _one_line(message: str | None) -> str:
    """An error message of a library on one line (OpenImageIO's can span several). OpenImageIO's
    advice to raise its size limit is dropped: a gigascroll user cannot (and the limit is what
    keeps a decompression bomb out)."""
    text = " ".join((message or "").split())
    cut = text.find(" If this is a valid file, raise the OIIO attribute")
    return text if cut < 0 else text[:cut] + " (refused as a possible decompression bomb)"


def open_image(image, name: str | None = None, band_rows: int = 0,
               colour: dict | None = None) -> ImageSource:
    """An ImageSource for a numpy array or an image file path. `colour`: options of
    .colour.plan_colour (mode, intent, black_point_compensation) to colour-manage the input
    and record it; None leaves the values as they are and records nothing."""
    if isinstance(image, ImageSource):
        return image
    if isinstance(image, np.ndarray):
        return ArraySource(image, name or "painting", band_rows or 256, colour)
    if isinstance(image, (str, os.PathLike)):
        return FileSource(image, name, band_rows, colour)
    raise ValueError(f"cannot read an image from {type(image).__name__}")

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


class FileSource(ImageSource):
    """An image file read through OpenImageIO, in bands aligned to its tile rows if tiled."""

    def __init__(self, path: str | os.PathLike, name: str | None = None, band_rows: int = 0,
                 colour: dict | None = None):
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
        self._plan = None
        if colour is not None:  # colour management (see .colour): profile or chromaticities
            try:
                icc = spec.getattribute("ICCProfile")
                plan = plan_colour(str(path), spec.nchannels,
                                   None if icc is None else np.asarray(icc, np.uint8).tobytes(),
                                   spec.getattribute("chromaticities"), **colour)
            except BaseException:
                inp.close()
                raise
            self.colour = plan.record
            if plan.transforms:
                self._plan = plan
                stored = f"{spec.format} read as {np.dtype(dtype).name}; "
                rest = describe_conversion(np.uint16, 1 if spec.nchannels <= 2 else 3)
                self.conversion = stored + plan.step() + "; " + rest
                if spec.nchannels in (2, 4) or spec.nchannels > 4:
                    self.conversion += "; extra channels (alpha) dropped"

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
            yield to_rgb8(data if self._plan is None else self._plan.apply(data))

    def close(self) -> None:
        if self._inp is not None:
            self._inp.close()
            self._inp = None


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

"""The built-in painting: a deterministic procedural ink landscape, rendered band by band
by the core (`render_ink_landscape`) and written as a tiled BigTIFF."""

from __future__ import annotations

from pathlib import Path

from .._core import render_ink_landscape
from ..outputs import atomic_file, oiio_reason

__all__ = ["synth_painting", "render_ink_landscape"]


def synth_painting(path, width: int, height: int, seed: int = 0, tile: int = 256,
                   compression: str = "none", progress: bool = False) -> Path:
    """Writes the built-in ink landscape (width x height, deterministic for a seed) as a tiled
    BigTIFF, band by band (one tile row at a time), never holding the whole image. The file is
    written under a temporary name and renamed when complete."""
    import OpenImageIO as oiio
    import numbers
    for label, v in (("width", width), ("height", height), ("tile", tile), ("seed", seed)):
        if not isinstance(v, numbers.Integral) or isinstance(v, bool):
            raise ValueError(f"synth_painting: {label} must be an integer, got {v!r}")
    width, height, tile = int(width), int(height), int(tile)
    if not 0 <= seed < 2**64:
        raise ValueError(f"synth_painting: seed must be in [0, 2^64), got {seed}")
    if width <= 0 or height <= 0:
        raise ValueError(f"painting size must be positive, got {width} x {height}")
    if width > (1 << 30) or height > (1 << 30):
        raise ValueError("painting is too large")
    if tile <= 0 or tile % 16:
        raise ValueError("TIFF tile size must be a positive multiple of 16")
    path = Path(path)
    spec = oiio.ImageSpec(width, height, 3, oiio.UINT8)
    spec.tile_width = spec.tile_height = tile
    spec.attribute("tiff:bigtiff", 1)
    spec.attribute("compression", compression)
    spec.attribute("Software", "gigascroll synth")
    spec.attribute("ImageDescription", f"gigascroll ink landscape, seed {seed}")
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=height, unit="row", desc="synth")
    try:
        with atomic_file(path, durable=True) as tmp:  # renamed into place when whole
            out = oiio.ImageOutput.create(str(tmp))
            if out is None or not out.open(str(tmp), spec):
                raise OSError(f"{path}: cannot write: {oiio.geterror()}")
            try:
                for y in range(0, height, tile):
                    rows = min(tile, height - y)
                    band = render_ink_landscape(width, height, y, rows, seed)
                    if not out.write_tiles(0, width, y, y + rows, 0, 1, band):
                        raise OSError(f"cannot write {path}: {oiio_reason(out, tmp)}")
                    if bar is not None:
                        bar.update(rows)
            finally:
                closed = out.close()
            if not closed:
                raise OSError(f"cannot write {path}: {oiio_reason(out, tmp)}")
    finally:
        if bar is not None:
            bar.close()
    return path

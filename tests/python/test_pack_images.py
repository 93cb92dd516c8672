"""Images read in bands and converted to 8-bit RGB (gigascroll.pack.images): files of every
kind OpenImageIO reads, and arrays."""

import numpy as np
import OpenImageIO as oiio
import pytest
from pack_reference import check_pack_against, write_image

import gigascroll
from gigascroll import build_pack


@pytest.mark.parametrize("kind", ["grey", "grey_alpha", "rgba", "16bit", "float", "tiled", "jpeg"])
def test_file_inputs_are_converted(tmp_path, kind, rng):
    if kind == "grey":
        pix = rng.integers(0, 256, (45, 71, 1), dtype=np.uint8)
        path = tmp_path / "grey.png"
        expect = np.repeat(pix, 3, axis=2)
    elif kind == "grey_alpha":
        pix = rng.integers(0, 256, (45, 71, 2), dtype=np.uint8)
        path = tmp_path / "ga.png"
        expect = np.repeat(pix[:, :, :1], 3, axis=2)
    elif kind == "rgba":
        pix = rng.integers(0, 256, (45, 71, 4), dtype=np.uint8)
        path = tmp_path / "rgba.png"
        expect = pix[:, :, :3]
    elif kind == "16bit":
        pix = rng.integers(0, 65536, (45, 71, 3), dtype=np.uint16)
        path = tmp_path / "deep.tif"
        expect = np.floor(pix / 257.0 + 0.5).astype(np.uint8)
    elif kind == "float":
        pix = (rng.random((45, 71, 3), dtype=np.float32) * 1.4 - 0.2).astype(np.float32)
        path = tmp_path / "linear.exr"
        x = np.clip(pix.astype(np.float64), 0, 1)
        srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
        expect = np.rint(srgb * 255).astype(np.uint8)
    elif kind == "jpeg":
        pix = rng.integers(0, 256, (61, 90, 3), dtype=np.uint8)
        path = tmp_path / "photo.jpg"
        expect = None  # lossy: compared with what OpenImageIO decodes below
    else:
        pix = rng.integers(0, 256, (300, 83, 3), dtype=np.uint8)
        path = tmp_path / "tiled.tif"
        spec = oiio.ImageSpec(83, 300, 3, oiio.UINT8)
        spec.tile_width = spec.tile_height = 32
        out = oiio.ImageOutput.create(str(path))
        assert out.open(str(path), spec)
        assert out.write_image(pix)
        out.close()
        expect = pix
    if kind != "tiled":
        write_image(path, pix)
    if expect is None:
        expect = oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)
    pack = build_pack(path, tmp_path / "p", tile_size=16, border=2)
    p = pack.paintings[0]
    assert p.name == path.stem and p.source == str(path)
    if kind == "float":
        # EXR stores half or float: compare against what the file really holds.
        stored = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)
        x = np.clip(stored.astype(np.float64), 0, 1)
        expect = np.rint(np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055) * 255).astype(np.uint8)
        assert "sRGB" in p.conversion
    if kind == "16bit":
        assert "uint16" in p.conversion
    if kind in ("grey", "grey_alpha"):
        assert "grey" in p.conversion
    if kind in ("rgba", "grey_alpha"):
        assert "alpha dropped" in p.conversion
    check_pack_against(pack, 0, expect)


def test_array_conversions():
    grey16 = np.array([[0, 257, 65535, 128]], np.uint16)
    out = gigascroll.to_rgb8(grey16)
    assert out.shape == (1, 4, 3) and out[0, :, 0].tolist() == [0, 1, 255, 0]
    with pytest.raises(ValueError, match="NaN"):
        gigascroll.to_rgb8(np.full((2, 2, 3), np.nan, np.float32))
    with pytest.raises(ValueError, match="unsupported"):
        gigascroll.to_rgb8(np.zeros((2, 2, 3), np.int64))

"""gigascroll export: every exported level equals the pack's level (exact for deflate,
within JPEG's tolerance otherwise), read back with independent readers (Pillow for the
JPEG tiles, OpenImageIO and libvips for the pyramidal TIFF), and the files follow their
formats' rules (IIIF Image API 3.0 info.json, Deep Zoom levels down to 1 x 1)."""

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import OpenImageIO as oiio
import pytest
from PIL import Image

from gigascroll import build_pack
from gigascroll.export import export_pack
from gigascroll.pack import read_level
from gigascroll.outputs import MARK, has_mark

W, H = 450, 300


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    """A smooth picture with some texture (JPEG errors stay small), 64-texel tiles, border
    4 (payload 56), plus a second painting."""
    y, x = np.mgrid[0:H, 0:W]
    img = np.stack([x * 255 / (W - 1), y * 255 / (H - 1),
                    128 + 60 * np.sin(x / 9.0) * np.cos(y / 7.0)], -1).astype(np.uint8)
    other = np.zeros((40, 30, 3), np.uint8) + 77
    root = tmp_path_factory.mktemp("export")
    return build_pack([img, other], root / "p", tile_size=64, border=4,
                      names=["scroll", "small"])


def jpeg_close(got, want):
    """JPEG at quality 95, 4:4:4: PSNR of at least 35 dB and no texel off by more than 32."""
    assert got.shape == want.shape
    err = got.astype(float) - want.astype(float)
    psnr = 10 * np.log10(255.0 ** 2 / max(np.mean(err ** 2), 1e-12))
    assert psnr >= 35 and np.abs(err).max() <= 32, (psnr, np.abs(err).max())


def check_iiif_info(info: dict, w: int, h: int, levels: int):
    """IIIF Image API 3.0: the required properties and level 0's rules."""
    assert info["@context"] == "http://iiif.io/api/image/3/context.json"
    for key in ("id", "type", "protocol", "profile", "width", "height"):
        assert key in info, key
    assert info["type"] == "ImageService3" and info["protocol"] == "http://iiif.io/api/image"
    assert info["profile"] in ("level0", "level1", "level2")
    assert (info["width"], info["height"]) == (w, h)
    assert isinstance(info["id"], str) and info["id"]
    (tiles,) = info["tiles"]
    assert isinstance(tiles["width"], int) and tiles["width"] > 0
    assert tiles["scaleFactors"] == [1 << l for l in range(levels)]
    for s in info["sizes"]:
        assert set(s) == {"width", "height"} and s["width"] <= w and s["height"] <= h


@pytest.mark.parametrize("reader", ["core", "python"])
def test_iiif_level0_tiles_equal_the_pack(pack, tmp_path, reader):
    out = export_pack(pack.path, tmp_path / "iiif", "iiif", quality=95, reader=reader)
    info = json.loads((out / "info.json").read_text())
    p = pack.paintings[0]
    check_iiif_info(info, W, H, p.levels)
    tw = info["tiles"][0]["width"]
    for l, s in enumerate(info["tiles"][0]["scaleFactors"]):
        ref = read_level(pack, 0, l)
        got = np.zeros_like(ref)
        # The IIIF 3.0 tile request rules, independently of the exporter's loops.
        for y in range(0, H, tw * s):
            for x in range(0, W, tw * s):
                rw, rh = min(tw * s, W - x), min(tw * s, H - y)
                sw, sh = math.ceil(rw / s), math.ceil(rh / s)
                f = out / f"{x},{y},{rw},{rh}" / f"{sw},{sh}" / "0" / "default.jpg"
                got[y // s:y // s + sh, x // s:x // s + sw] = np.asarray(Image.open(f))
        jpeg_close(got, ref)
    for size in info["sizes"]:
        f = out / "full" / f"{size['width']},{size['height']}" / "0" / "default.jpg"
        assert Image.open(f).size == (size["width"], size["height"])


@pytest.mark.parametrize("reader", ["core", "python"])
def test_dzi_levels_down_to_one_pixel(pack, tmp_path, reader):
    dzi = export_pack(pack.path, tmp_path / "deep", "dzi", painting="scroll", quality=95,
                      reader=reader)
    assert dzi.name == "deep.dzi"
    root = ET.parse(dzi).getroot()
    ns = "{http://schemas.microsoft.com/deepzoom/2008}"
    size = root.find(f"{ns}Size")
    assert (int(size.get("Width")), int(size.get("Height"))) == (W, H)
    T, overlap = int(root.get("TileSize")), int(root.get("Overlap"))
    assert (T, overlap, root.get("Format")) == (pack.payload, pack.border, "jpg")
    files = tmp_path / "deep_files"
    top = math.ceil(math.log2(max(W, H)))
    assert sorted(int(d.name) for d in files.iterdir() if d.name != MARK) == list(range(top + 1))
    assert has_mark(files, "export", format="dzi")
    p = pack.paintings[0]
    for dz in range(top + 1):
        s = 1 << (top - dz)
        w, h = math.ceil(W / s), math.ceil(H / s)
        got = np.zeros((h, w, 3), np.uint8)
        for row in range(math.ceil(h / T)):
            for col in range(math.ceil(w / T)):
                t = np.asarray(Image.open(files / str(dz) / f"{col}_{row}.jpg"))
                x0, y0 = col * T - (overlap if col else 0), row * T - (overlap if row else 0)
                assert t.shape[1] == min(w, (col + 1) * T + overlap) - x0
                assert t.shape[0] == min(h, (row + 1) * T + overlap) - y0
                got[y0:y0 + t.shape[0], x0:x0 + t.shape[1]] = t
        if top - dz < p.levels:
            jpeg_close(got, read_level(pack, 0, top - dz))
        if dz == 0:
            assert (h, w) == (1, 1)


@pytest.mark.parametrize("compression, reader", [("deflate", "core"), ("deflate", "python"),
                                                 ("jpeg", "core")])
def test_pyramidal_tiff_level_by_level(pack, tmp_path, compression, reader):
    import pyvips
    out = export_pack(pack.path, tmp_path / "pyr.tif", "tiff", compression=compression,
                      quality=95, reader=reader)
    p = pack.paintings[0]
    inp = oiio.ImageInput.open(str(out))
    assert inp is not None, oiio.geterror()
    n = 0
    while inp.seek_subimage(n, 0):
        spec = inp.spec()
        assert spec.tile_width == 256 and spec.get_string_attribute("compression") == (
            "zip" if compression == "deflate" else "jpeg")
        got = inp.read_image(n, 0, 0, 3, oiio.UINT8)
        ref = read_level(pack, 0, n)
        if compression == "deflate":
            np.testing.assert_array_equal(got, ref)
        else:
            jpeg_close(got, ref)
        n += 1
    inp.close()
    assert n == p.levels
    assert open(out, "rb").read(4) == b"II+\0"  # BigTIFF
    assert pyvips.Image.new_from_file(str(out)).get("n-pages") == p.levels
    for l in range(p.levels):
        got = pyvips.Image.new_from_file(str(out), page=l).numpy()
        if compression == "deflate":
            np.testing.assert_array_equal(got, read_level(pack, 0, l))
        else:
            jpeg_close(got, read_level(pack, 0, l))


def test_export_errors_and_atomic_output(pack, tmp_path, gigascroll_cli):
    with pytest.raises(ValueError, match="no painting 'nope'"):
        export_pack(pack.path, tmp_path / "x", "iiif", painting="nope")
    with pytest.raises(ValueError, match="unknown export format"):
        export_pack(pack.path, tmp_path / "x", "png")
    with pytest.raises(ValueError, match="quality"):
        export_pack(pack.path, tmp_path / "x", "iiif", quality=0)
    with pytest.raises(OSError, match="no such directory"):
        export_pack(pack.path, tmp_path / "missing" / "x", "tiff")
    for fmt in ("iiif", "dzi", "tiff"):  # a directory nobody can create files in (even root)
        with pytest.raises(OSError, match="cannot write /proc/x"):
            export_pack(pack.path, "/proc/x", fmt)
    export_pack(pack.path, tmp_path / "small", "iiif", painting="small")
    with pytest.raises(OSError, match="already exists"):
        export_pack(pack.path, tmp_path / "small", "iiif", painting="small")
    export_pack(pack.path, tmp_path / "small", "iiif", painting=1, force=True)
    assert sorted(f.name for f in tmp_path.iterdir()) == ["small"]  # no temporary left
    r = gigascroll_cli("export", pack.path, "-o", tmp_path / "y", "--format", "dzi",
                       "--painting", "nope")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "no painting" in r.stderr
    r = gigascroll_cli("export", pack.path, "-o", tmp_path / "cli.tif", "--format", "tiff",
                       "--compression", "deflate", "--painting", "small")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "cli.tif").is_file()

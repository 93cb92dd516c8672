"""Image files that used to pack "successfully" into wrong data (gigascroll.pack.images):
a truncated JPEG fails; a CMYK TIFF goes through its CMYK profile (or the default one) and
matches LittleCMS as Pillow drives it; signed 16-bit samples map as the note says; tiles much
taller than a band keep memory at a band of the image's width."""

import io
import json
import subprocess
import sys

import numpy as np
import pytest
from pack_reference import check_pack_against

from gigascroll import build_pack
from gigascroll.cli import main as cli_main
from gigascroll.pack.colour import default_cmyk_profile

tifffile = pytest.importorskip("tifffile")
Image = pytest.importorskip("PIL.Image")
ImageCms = pytest.importorskip("PIL.ImageCms")


def manifest(path):
    return json.loads((path / "manifest.json").read_text())


def level0(pack, img_shape):
    """Level 0 of painting 0 reassembled from its tiles (no borders)."""
    T, b = pack.tile_size, pack.border
    P = T - 2 * b
    h, w = img_shape[:2]
    out = np.zeros((h, w, 3), np.uint8)
    for ty in range(-(-h // P)):
        for tx in range(-(-w // P)):
            tile = pack.read_tile(0, 0, tx, ty)
            y, x = ty * P, tx * P
            out[y:y + P, x:x + P] = tile[b:b + min(P, h - y), b:b + min(P, w - x)]
    return out


def test_truncated_jpeg_fails_clearly(tmp_path, capsys):
    img = np.random.default_rng(0).integers(0, 256, (300, 200, 3), np.uint8)
    Image.fromarray(img).save(tmp_path / "a.jpg", quality=90)
    data = (tmp_path / "a.jpg").read_bytes()
    (tmp_path / "t.jpg").write_bytes(data[:len(data) // 2])
    with pytest.raises(OSError, match="truncated"):
        build_pack(tmp_path / "t.jpg", tmp_path / "p", tile_size=16, border=2)
    assert not (tmp_path / "p").exists() and not list(tmp_path.glob("p.tmp-*"))
    assert cli_main(["pack", str(tmp_path / "t.jpg"), "-o", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after the progress bar
    assert err.startswith("gigascroll pack: error:") and "Premature end" in err
    # the whole file still packs
    build_pack(tmp_path / "a.jpg", tmp_path / "ok", tile_size=16, border=2)


def _cmyk_reference(cmyk: np.ndarray, profile: bytes) -> np.ndarray:
    """LittleCMS through Pillow, unoptimised (no 8-bit CLUT resampling), relative + BPC."""
    out = ImageCms.profileToProfile(
        Image.fromarray(cmyk, "CMYK"), ImageCms.ImageCmsProfile(io.BytesIO(profile)),
        ImageCms.createProfile("sRGB"), renderingIntent=ImageCms.Intent.RELATIVE_COLORIMETRIC,
        outputMode="RGB",
        flags=ImageCms.Flags.BLACKPOINTCOMPENSATION | ImageCms.Flags.NOOPTIMIZE)
    return np.asarray(out)


@pytest.mark.parametrize("embedded", [False, True])
def test_cmyk_tiff_converts_through_its_profile(tmp_path, embedded):
    profile = default_cmyk_profile()
    if profile is None:
        pytest.skip("no default CMYK profile installed (libgs-common)")
    rng = np.random.default_rng(1)
    cmyk = rng.integers(0, 256, (40, 56, 4), np.uint8)
    cmyk[:8, :8] = (255, 0, 0, 0)  # pure cyan: must come out cyan-ish, not red
    extratags = [(34675, "B", len(profile), profile, True)] if embedded else []
    tifffile.imwrite(tmp_path / "c.tif", cmyk, photometric="separated", extratags=extratags)
    pack = build_pack(tmp_path / "c.tif", tmp_path / "p", tile_size=16, border=2)
    got = level0(pack, cmyk.shape)
    ref = _cmyk_reference(cmyk, profile)
    assert np.abs(got.astype(int) - ref).max() <= 1
    r, g, b = got[:8, :8].reshape(-1, 3).mean(0)
    assert r < 60 and g > 120 and b > 180  # cyan
    p = manifest(tmp_path / "p")["paintings"][0]
    assert "CMYK" in p["conversion"] and "alpha" not in p["conversion"]
    assert ("assumed" in p["conversion"]) != embedded
    assert p["colour"]["source_space"] == ("embedded ICC profile" if embedded else "default CMYK profile")
    assert p["colour"]["profile"]["colour_space"] == "CMYK"
    with pytest.raises(ValueError, match="CMYK image cannot be stored untouched"):
        build_pack(tmp_path / "c.tif", tmp_path / "k", colour="keep")


def test_cmyk_with_an_rgb_profile_is_refused(tmp_path):
    from gigascroll.pack.colour import rgb_profile, REC709_CHROMATICITIES
    rgb = rgb_profile(REC709_CHROMATICITIES, "srgb", "an RGB profile")
    cmyk = np.zeros((8, 8, 4), np.uint8)
    tifffile.imwrite(tmp_path / "c.tif", cmyk, photometric="separated",
                     extratags=[(34675, "B", len(rgb), rgb, True)])
    with pytest.raises(ValueError, match="does not match"):
        build_pack(tmp_path / "c.tif", tmp_path / "p")
    assert not any(p.name.startswith("p") for p in tmp_path.iterdir())


def test_signed_16_bit_samples_map_as_the_note_says(tmp_path):
    rng = np.random.default_rng(2)
    s16 = rng.integers(-32768, 32768, (30, 40, 3)).astype(np.int16)
    s16[0, 0] = (-1, 0, 32767)
    tifffile.imwrite(tmp_path / "s.tif", s16, photometric="rgb")
    pack = build_pack(tmp_path / "s.tif", tmp_path / "p", tile_size=16, border=2)
    # The documented mapping: negative -> 0, [0, 32767] -> [0, 65535], then round(v / 257).
    u16 = np.rint(np.clip(s16.astype(np.float64), 0, None) * 65535 / 32767)
    ref = np.rint(u16 / 257).astype(np.uint8)
    got = level0(pack, s16.shape)
    assert np.abs(got.astype(int) - ref).max() <= 1
    assert tuple(got[0, 0]) == (0, 0, 255)
    note = manifest(tmp_path / "p")["paintings"][0]["conversion"]
    assert "negative values clamped to 0" in note and "32767" in note


def test_tall_tiles_pack_correctly(tmp_path, monkeypatch):
    import gigascroll.pack.images as images
    monkeypatch.setattr(images, "TALL_TILE_BYTES", 1024)
    img = np.random.default_rng(3).integers(0, 256, (700, 300, 3), np.uint8)
    tifffile.imwrite(tmp_path / "t.tif", img, tile=(1024, 32))  # one tile row, 32 wide
    pack = build_pack(tmp_path / "t.tif", tmp_path / "p", tile_size=16, border=2, band_rows=100)
    check_pack_against(pack, 0, img)


# Peak memory of the child itself: VmHWM (reset by exec) rather than getrusage's ru_maxrss,
# which a forked child inherits from the (large) test process on Linux.
_PEAK = """
import resource, sys
def peak():
    try:
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
import gigascroll, gigascroll.pack.images as im
im.TALL_TILE_BYTES = 1 << 20  # the test's image is small: scale the thresholds with it
im.BAND_BYTES = 1 << 20
if sys.argv[3] == "whole-tile-rows":  # the old behaviour, to show the test can tell
    im.TALL_TILE_BANDS = 1 << 30
import OpenImageIO  # imported before the baseline: its own memory is not the band's
before = peak()
gigascroll.build_pack(sys.argv[1], sys.argv[2], tile_size=128, border=4, codec="zstd", threads=1)
print(peak() - before)
"""


def _peak_growth(src, out, mode="default") -> int:
    r = subprocess.run([sys.executable, "-c", _PEAK, str(src), str(out), mode],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return int(r.stdout.strip())


def test_tall_tiles_keep_memory_band_limited(tmp_path):
    h, w = 3072, 3072
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([x % 256, y % 256, (x + y) % 256], -1).astype(np.uint8)
    tifffile.imwrite(tmp_path / "tall.tif", img, tile=(h, 16), compression="zlib")
    tifffile.imwrite(tmp_path / "square.tif", img, tile=(128, 128), compression="zlib")
    tile_row = h * w * 3  # what reading a whole tile row holds at once (27 MB)
    banded = _peak_growth(tmp_path / "square.tif", tmp_path / "a")  # the band-limited expectation
    tall = _peak_growth(tmp_path / "tall.tif", tmp_path / "b")
    whole = _peak_growth(tmp_path / "tall.tif", tmp_path / "c", "whole-tile-rows")
    assert tall <= banded + tile_row // 4, (tall, banded)
    assert whole > banded + tile_row, (whole, banded)  # the old way: several tile rows


def test_decompression_bomb_is_one_clear_line(tmp_path, capsys):
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    w = h = 200000  # 120 GB claimed by a file of a few hundred bytes
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(b"\0" * (1 + 3 * w))) + chunk(b"IEND", b""))
    (tmp_path / "bomb.png").write_bytes(png)
    assert cli_main(["pack", str(tmp_path / "bomb.png"), "-o", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "200000x200000" in err[0] and "decompression bomb" in err[0]
    assert "OIIO attribute" not in err[0]  # advice a gigascroll user cannot follow
    assert not (tmp_path / "p").exists()

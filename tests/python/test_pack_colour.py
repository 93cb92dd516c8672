"""Colour-managed ingest: inputs with an embedded ICC profile (or EXR chromaticities) are
stored as sRGB. The builder converts with LittleCMS linked by the core; the references are
independent of it: colour-science (the colour spaces' published definitions, in numpy) for
every bit depth, and LittleCMS through Pillow's ImageCms binding for 8-bit inputs."""

import io
import json
import warnings
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from PIL import Image, ImageCms

from gigascroll import build_pack
from gigascroll.pack import read_level
from gigascroll.pack.colour import grey_profile, parse_icc, rgb_profile

from pack_reference import check_pack_against

with warnings.catch_warnings():  # colour-science warns that scipy-only features are missing
    warnings.simplefilter("ignore")
    import colour

D65, D50 = (0.3127, 0.3290), (0.3457, 0.3585)
# name: (chromaticities, tone curve for rgb_profile, colour-science colour space)
SPACES = {
    "adobe-rgb": ((0.64, 0.33, 0.21, 0.71, 0.15, 0.06, *D65), 563 / 256, "Adobe RGB (1998)"),
    # L* tone curve: Y = ((V + 0.16) / 1.16)^3 above V = 0.08, V / 9.033 below.
    "eci-rgb-v2": ((0.67, 0.33, 0.21, 0.71, 0.14, 0.08, *D50),
                   (3.0, 1 / 1.16, 0.16 / 1.16, 1 / 9.033, 0.08), "ECI RGB v2"),
    "prophoto": ((0.7347, 0.2653, 0.1596, 0.8404, 0.0366, 0.0001, *D50),
                 (1.8, 1.0, 0.0, 1 / 16, 1 / 32), "ProPhoto RGB"),
    "display-p3": ((0.680, 0.320, 0.265, 0.690, 0.150, 0.060, *D65), "srgb", "Display P3"),
}
GREY_GAMMA = 2.2


def profile_bytes(name: str) -> bytes:
    if name == "grey-2.2":
        return grey_profile(GREY_GAMMA, "Grey gamma 2.2")
    chrom, trc, _ = SPACES[name]
    return rgb_profile(chrom, trc, f"{name} (test)")


def write_tagged(path, pixels, icc: bytes | None = None, chromaticities=None):
    pixels = np.ascontiguousarray(pixels)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    fmt = {np.dtype(np.uint8): oiio.UINT8, np.dtype(np.uint16): oiio.UINT16,
           np.dtype(np.float32): oiio.FLOAT}[pixels.dtype]
    if str(path).endswith(".exr"):
        fmt = oiio.HALF
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], fmt)
    if icc is not None:
        spec.attribute("ICCProfile", oiio.TypeDesc(f"uint8[{len(icc)}]"), np.frombuffer(icc, np.uint8))
    if chromaticities is not None:
        spec.attribute("chromaticities", oiio.TypeDesc("float[8]"), tuple(chromaticities))
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(pixels), out.geterror()
    out.close()


def srgb8(v: np.ndarray) -> np.ndarray:
    return np.rint(np.clip(v, 0.0, 1.0) * 255.0)


def reference_colour_science(name: str, values01: np.ndarray, linear: bool = False) -> np.ndarray:
    """Values in [0, 1] (encoded in the source space, or linear light) -> sRGB 8-bit."""
    if name == "grey-2.2":
        Y = np.clip(values01, 0, 1) ** GREY_GAMMA
        return srgb8(colour.cctf_encoding(np.repeat(Y[..., None], 3, -1), "sRGB"))
    space = colour.RGB_COLOURSPACES[SPACES[name][2]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = colour.RGB_to_RGB(np.clip(values01, 0, 1), space, colour.RGB_COLOURSPACES["sRGB"],
                                chromatic_adaptation_transform="Bradford",
                                apply_cctf_decoding=not linear, apply_cctf_encoding=True)
    return srgb8(out)


def reference_pillow(icc: bytes, pixels8: np.ndarray) -> np.ndarray:
    mode = "L" if pixels8.ndim == 2 else "RGB"
    t = ImageCms.buildTransform(ImageCms.ImageCmsProfile(io.BytesIO(icc)),
                                ImageCms.createProfile("sRGB"), mode, "RGB",
                                renderingIntent=ImageCms.Intent.RELATIVE_COLORIMETRIC,
                                flags=ImageCms.Flags.BLACKPOINTCOMPENSATION)
    return np.asarray(ImageCms.applyTransform(Image.fromarray(pixels8, mode), t)).astype(np.float64)


def random_pixels(dtype, grey: bool, seed: int):
    rng = np.random.default_rng(seed)
    shape = (37, 53) if grey else (37, 53, 3)
    if dtype == np.uint8:
        a = rng.integers(0, 256, shape, dtype=np.uint8)
        return a, a / 255.0
    if dtype == np.uint16:
        a = rng.integers(0, 65536, shape, dtype=np.uint16)
        return a, a / 65535.0
    a = (rng.random(shape, dtype=np.float32) * 1.1 - 0.05).astype(np.float32)
    return a, np.rint(np.clip(a, 0, 1) * 65535) / 65535  # the builder works at 16 bits


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32], ids=["u8", "u16", "f32"])
@pytest.mark.parametrize("name", [*SPACES, "grey-2.2"])
def test_profiles_convert_to_srgb_within_one_lsb(tmp_path, name, dtype):
    icc = profile_bytes(name)
    pixels, values = random_pixels(dtype, name == "grey-2.2", seed=len(name))
    write_tagged(tmp_path / "in.tif", pixels, icc)
    pack = build_pack(tmp_path / "in.tif", tmp_path / "p", tile_size=32, border=2)
    got = read_level(pack, 0, 0).astype(np.float64)
    err = np.abs(got - reference_colour_science(name, values))
    assert err.max() <= 1, (name, err.max(), (err > 0).mean())
    if dtype == np.uint8:
        err = np.abs(got - reference_pillow(icc, pixels))
        assert err.max() <= 1, (name, err.max())
    # The mip chain is the exact average of the converted level 0.
    check_pack_against(pack, 0, got.astype(np.uint8))
    c = pack.paintings[0].colour
    assert c["mode"] == "convert" and c["source_space"] == "embedded ICC profile"
    assert c["profile"]["description"] == parse_icc(icc).description
    assert c["profile"]["sha256"] == parse_icc(icc).sha256 and c["profile"]["bytes"] == len(icc)
    assert c["intent"] == "relative" and c["black_point_compensation"] is True
    assert "LittleCMS" in c["transform"] and "colour" in pack.paintings[0].conversion


DEBIAN_PROFILES = ["AdobeRGB1998.icc", "ECI-RGBv2.icc", "ProPhotoRGB.icc"]


@pytest.mark.parametrize("filename", DEBIAN_PROFILES)
def test_published_profiles_from_debian(tmp_path, filename):
    """The same check with real published profiles (Debian's colord-data) where installed."""
    path = Path("/usr/share/color/icc/colord") / filename
    if not path.is_file():
        pytest.skip(f"{path} not installed (Debian package colord-data)")
    icc = path.read_bytes()
    pixels, _ = random_pixels(np.uint8, False, seed=3)
    write_tagged(tmp_path / "in.tif", pixels, icc)
    got = read_level(build_pack(tmp_path / "in.tif", tmp_path / "p", tile_size=32, border=2), 0, 0)
    # The file defines the space (colord's ProPhoto, for one, is a pure gamma 1.8 without
    # the standard's linear toe), so the reference is the file read by another binding.
    assert np.abs(got - reference_pillow(icc, pixels)).max() <= 1


def test_display_p3_example_from_the_issue(tmp_path):
    """sRGB (200, 40, 40) encoded in Display P3 is (184, 56, 49); it is stored as sRGB again."""
    icc = profile_bytes("display-p3")
    write_tagged(tmp_path / "p3.tif", np.full((8, 8, 3), (184, 56, 49), np.uint8), icc)
    pack = build_pack(tmp_path / "p3.tif", tmp_path / "p", tile_size=16, border=2)
    got = read_level(pack, 0, 0)
    assert np.abs(got.astype(int) - (200, 40, 40)).max() <= 1
    assert pack.paintings[0].conversion != "none (8-bit RGB)"


def test_untagged_is_assumed_srgb_and_untouched(tmp_path):
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    write_tagged(tmp_path / "plain.tif", pixels)
    pack = build_pack(tmp_path / "plain.tif", tmp_path / "p", tile_size=16, border=2)
    np.testing.assert_array_equal(read_level(pack, 0, 0), pixels)
    p = pack.paintings[0]
    assert p.conversion == "none (8-bit RGB)"
    assert p.colour["source_space"] == "assumed sRGB" and p.colour["profile"] is None
    assert p.colour["transform"] == "none"
    arr = build_pack(pixels, tmp_path / "a", tile_size=16, border=2)  # arrays too
    assert arr.paintings[0].colour["source_space"] == "assumed sRGB"
    for f in ("tiles-00000.bin", "index.bin"):  # the same bytes either way
        assert (tmp_path / "p" / f).read_bytes() == (tmp_path / "a" / f).read_bytes()


def test_keep_stores_values_untouched_and_says_so(tmp_path):
    icc = profile_bytes("adobe-rgb")
    pixels = np.random.default_rng(2).integers(0, 256, (20, 24, 3), dtype=np.uint8)
    write_tagged(tmp_path / "in.tif", pixels, icc)
    pack = build_pack(tmp_path / "in.tif", tmp_path / "p", tile_size=16, border=2, colour="keep")
    np.testing.assert_array_equal(read_level(pack, 0, 0), pixels)
    c = pack.paintings[0].colour
    assert c["mode"] == "keep" and c["stored_space"] == "source"
    assert c["profile"]["sha256"] == parse_icc(icc).sha256 and c["transform"].startswith("none")


def test_intent_is_recorded_and_unknown_intent_refused(tmp_path):
    icc = profile_bytes("prophoto")
    write_tagged(tmp_path / "in.tif", np.zeros((4, 4, 3), np.uint8) + 100, icc)
    pack = build_pack(tmp_path / "in.tif", tmp_path / "p", tile_size=16, border=2,
                      intent="perceptual", black_point_compensation=False)
    c = pack.paintings[0].colour
    assert (c["intent"], c["black_point_compensation"]) == ("perceptual", False)
    with pytest.raises(ValueError, match="unknown rendering intent 'vivid'"):
        build_pack(tmp_path / "in.tif", tmp_path / "q", intent="vivid")
    with pytest.raises(ValueError, match="unknown colour mode"):
        build_pack(tmp_path / "in.tif", tmp_path / "q", colour="maybe")
    assert not (tmp_path / "q").exists()


def _patched(icc: bytes, offset: int, value: bytes) -> bytes:
    b = bytearray(icc)
    b[offset:offset + len(value)] = value
    return bytes(b)


@pytest.mark.parametrize("kind, message", [
    ("truncated", "corrupt ICC profile"),
    ("garbage", "corrupt ICC profile"),
    ("cmyk", "CMYK ICC profile does not match"),
    ("link", "device link"),
    ("grey-on-rgb", "does not match"),
    ("bad-tags", "ICC profile"),
])
def test_unusable_profiles_are_clear_errors(tmp_path, gigascroll_cli, kind, message):
    icc = profile_bytes("adobe-rgb")
    bad = {"truncated": icc[:100], "garbage": b"\x00" * 40 + icc[40:],
           "cmyk": _patched(icc, 16, b"CMYK"), "link": _patched(icc, 12, b"link"),
           "grey-on-rgb": profile_bytes("grey-2.2"),
           "bad-tags": _patched(icc, 132 + 12 * 4 + 4, b"\x00\x00\x00\x00")}[kind]
    write_tagged(tmp_path / "in.tif", np.zeros((4, 4, 3), np.uint8), bad)
    with pytest.raises(ValueError, match=message):
        build_pack(tmp_path / "in.tif", tmp_path / "p")
    assert not (tmp_path / "p").exists() and not list(tmp_path.glob("p.tmp-*"))
    if kind == "cmyk":  # the command line: one line, exit code 2
        r = gigascroll_cli("pack", tmp_path / "in.tif", "-o", tmp_path / "p")
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "CMYK" in r.stderr


def test_exr_chromaticities_are_honoured(tmp_path):
    chrom = SPACES["display-p3"][0]
    rng = np.random.default_rng(5)
    linear = (rng.random((24, 40, 3)) * 1.05).astype(np.float32)
    write_tagged(tmp_path / "p3.exr", linear, chromaticities=chrom)
    pack = build_pack(tmp_path / "p3.exr", tmp_path / "p", tile_size=16, border=2)
    stored = linear.astype(np.float16).astype(np.float64)  # the file holds half floats
    ref = reference_colour_science("display-p3", np.rint(np.clip(stored, 0, 1) * 65535) / 65535,
                                   linear=True)
    assert np.abs(read_level(pack, 0, 0) - ref).max() <= 1
    c = pack.paintings[0].colour
    assert c["source_space"] == "EXR chromaticities" and c["chromaticities"] == pytest.approx(chrom)
    # Rec. 709 chromaticities are sRGB's own: no transform, the same bytes as untagged.
    write_tagged(tmp_path / "709.exr", linear, chromaticities=(0.64, 0.33, 0.30, 0.60, 0.15, 0.06, *D65))
    write_tagged(tmp_path / "plain.exr", linear)
    a = build_pack(tmp_path / "709.exr", tmp_path / "a", tile_size=16, border=2)
    build_pack(tmp_path / "plain.exr", tmp_path / "b", tile_size=16, border=2)
    assert a.paintings[0].colour["transform"] == "none"
    assert (tmp_path / "a/tiles-00000.bin").read_bytes() == (tmp_path / "b/tiles-00000.bin").read_bytes()


def test_manifest_colour_validates_against_schema(tmp_path):
    import jsonschema
    from gigascroll.pack.reader import manifest_schema
    write_tagged(tmp_path / "in.tif", np.zeros((4, 4, 3), np.uint8), profile_bytes("display-p3"))
    build_pack(tmp_path / "in.tif", tmp_path / "p", tile_size=16, border=2)
    m = json.loads((tmp_path / "p/manifest.json").read_text())
    jsonschema.validate(m, manifest_schema(), cls=jsonschema.Draft202012Validator)
    assert m["paintings"][0]["colour"]["profile"]["description"] == "display-p3 (test)"

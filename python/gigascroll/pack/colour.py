"""Colour-managed ingest: an input's embedded ICC profile (or an EXR's chromaticities) is
converted to sRGB with LittleCMS 2 (linked by the core: gigascroll._core.IccTransform), band
by band.

Every band is transformed to 16 bits per channel (16-bit and float inputs through
LittleCMS' float pipeline, floats clamped to [0, 1] and quantised to 16 bits first; 8-bit
RGB inputs of matrix/TRC profiles through its matrix-shaper path) and then rounded to 8 bits
like any 16-bit input, so the mip chain (built by the core from level 0) stays the exact average of the
converted pixels. A profile that cannot be used (corrupt, CMYK or another colour space, a
device link, abstract or named-colour profile, or one that does not match the image's
channels) is a ValueError, never a silent pass-through.

The manifest records per painting a `colour` object (schema in manifest.schema.json):
mode (convert | keep), source_space, the profile's description, SHA-256 and size, the
rendering intent, black-point compensation and the transform applied."""

from __future__ import annotations

import hashlib
import struct
from dataclasses import dataclass, field

import numpy as np

__all__ = ["INTENTS", "COLOUR_MODES", "ProfileInfo", "parse_icc", "rgb_profile", "grey_profile",
           "ColourPlan", "plan_colour", "REC709_CHROMATICITIES"]

# LittleCMS / ICC rendering intents by their command-line names.
INTENTS = {"perceptual": "perceptual", "relative": "relative", "saturation": "saturation",
           "absolute": "absolute"}
COLOUR_MODES = ("convert", "keep")
# EXR's default (Rec. 709 / sRGB primaries, D65 white): red, green, blue, white (x, y).
REC709_CHROMATICITIES = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)
_USABLE_CLASSES = {b"mntr": "mntr", b"scnr": "scnr", b"prtr": "prtr", b"spac": "spac"}
_CLASS_NAMES = {b"link": "a device link", b"abst": "an abstract profile",
                b"nmcl": "a named-colour profile"}
_SPACES = {b"RGB ": "RGB", b"GRAY": "GRAY", b"CMYK": "CMYK"}
# The CMYK profile assumed for a CMYK image without an embedded one: Ghostscript's default
# (SWOP-like press characterisation, Debian package libgs-common).
DEFAULT_CMYK_PROFILES = ("/usr/share/color/icc/ghostscript/default_cmyk.icc",)


def default_cmyk_profile() -> bytes | None:
    """The bytes of the first installed default CMYK profile, None when there is none."""
    for path in DEFAULT_CMYK_PROFILES:
        try:
            with open(path, "rb") as f:
                return f.read()
        except OSError:
            continue
    return None


# ----------------------------------------------------------------------------- reading profiles

@dataclass(frozen=True)
class ProfileInfo:
    description: str
    sha256: str
    size: int
    colour_space: str  # "RGB" or "GRAY"
    device_class: str

    def record(self) -> dict:
        return {"description": self.description, "sha256": self.sha256, "bytes": self.size,
                "colour_space": self.colour_space, "class": self.device_class}


def _text_tag(data: bytes, offset: int, size: int) -> str:
    kind = data[offset:offset + 4]
    if kind == b"desc" and size >= 12:  # ICC v2 textDescriptionType: ASCII count + text
        n = struct.unpack_from(">I", data, offset + 8)[0]
        return data[offset + 12:offset + 12 + min(n, size - 12)].split(b"\0")[0].decode("latin-1")
    if kind == b"mluc" and size >= 16:  # ICC v4 multiLocalizedUnicodeType: first record
        count, rec = struct.unpack_from(">II", data, offset + 8)
        if count and rec >= 12:
            length, start = struct.unpack_from(">II", data, offset + 16 + 4)
            raw = data[offset + start:offset + start + length]
            return raw.decode("utf-16-be", errors="replace").rstrip("\0")
    if kind == b"text":
        return data[offset + 8:offset + size].split(b"\0")[0].decode("latin-1")
    return ""


def parse_icc(data: bytes, where: str = "ICC profile") -> ProfileInfo:
    """Checks an ICC profile's header and tag table and returns what the manifest records.
    ValueError for a corrupt profile, an unsupported colour space (CMYK, Lab, ...) or class
    (device link, abstract, named colour)."""
    data = bytes(data)
    if len(data) < 132:
        raise ValueError(f"{where}: corrupt ICC profile ({len(data)} bytes, too short)")
    size, = struct.unpack_from(">I", data, 0)
    if data[36:40] != b"acsp" or size > len(data) or size < 132:
        raise ValueError(f"{where}: corrupt ICC profile (bad header)")
    data = data[:size]
    cls, space = data[12:16], data[16:20]
    if cls in _CLASS_NAMES:
        raise ValueError(f"{where}: the embedded ICC profile is {_CLASS_NAMES[cls]}, which "
                         "cannot describe an image's colours")
    if cls not in _USABLE_CLASSES:
        raise ValueError(f"{where}: corrupt ICC profile (unknown class {cls!r})")
    if space not in _SPACES:
        name = space.decode("latin-1").strip() or "unknown"
        raise ValueError(f"{where}: unsupported ICC colour space {name} (only RGB, grey and "
                         "CMYK images can be converted; convert it to RGB first)")
    count, = struct.unpack_from(">I", data, 128)
    if 132 + 12 * count > size:
        raise ValueError(f"{where}: corrupt ICC profile (tag table overruns the profile)")
    desc = ""
    for i in range(count):
        sig, off, n = struct.unpack_from(">4sII", data, 132 + 12 * i)
        if off + n > size or n < 8:
            raise ValueError(f"{where}: corrupt ICC profile (tag {sig!r} outside the profile)")
        if sig == b"desc":
            desc = _text_tag(data, off, n)
    return ProfileInfo(desc or "(no description)", hashlib.sha256(data).hexdigest(), size,
                       _SPACES[space], _USABLE_CLASSES[cls])


# ----------------------------------------------------------------------------- making profiles

_D50 = np.array([0.9642, 1.0, 0.8249])
_BRADFORD = np.array([[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367],
                      [0.0389, -0.0685, 1.0296]])


def _xy_to_XYZ(x: float, y: float) -> np.ndarray:
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def _adapt_to_d50(white_XYZ: np.ndarray) -> np.ndarray:
    """Bradford chromatic adaptation matrix from `white_XYZ` to the ICC PCS white (D50)."""
    s, d = _BRADFORD @ white_XYZ, _BRADFORD @ _D50
    return np.linalg.inv(_BRADFORD) @ np.diag(d / s) @ _BRADFORD


def _rgb_to_xyz(chromaticities) -> tuple[np.ndarray, np.ndarray]:
    """RGB -> XYZ matrix of the primaries (columns: XYZ of R, G, B) and the white's XYZ."""
    rx, ry, gx, gy, bx, by, wx, wy = map(float, chromaticities)
    P = np.column_stack([_xy_to_XYZ(rx, ry), _xy_to_XYZ(gx, gy), _xy_to_XYZ(bx, by)])
    W = _xy_to_XYZ(wx, wy)
    return P * np.linalg.solve(P, W), W


def _s15(v: float) -> bytes:
    return struct.pack(">i", int(round(v * 65536)))


def _xyz_tag(XYZ) -> bytes:
    return b"XYZ \0\0\0\0" + b"".join(_s15(c) for c in XYZ)


def _curve_tag(trc) -> bytes:
    """trc: a gamma (float) or ("srgb",) / a parametric curve (g, a, b, c, d) of ICC type 3."""
    if isinstance(trc, (int, float)):
        return b"curv\0\0\0\0" + struct.pack(">IH", 1, int(round(trc * 256))) + b"\0\0"
    params = (2.4, 1 / 1.055, 0.055 / 1.055, 1 / 12.92, 0.04045) if trc == "srgb" else tuple(trc)
    return b"para\0\0\0\0" + struct.pack(">HH", 3, 0) + b"".join(_s15(p) for p in params)


def _desc_tag(text: str) -> bytes:
    t = text.encode("ascii", "replace") + b"\0"
    return b"desc\0\0\0\0" + struct.pack(">I", len(t)) + t + b"\0" * (4 + 4 + 2 + 1 + 67)


def _assemble(space: bytes, tags: list[tuple[bytes, bytes]]) -> bytes:
    """An ICC v2.4 display (mntr) profile with PCS XYZ from (signature, data) tags."""
    table, body = [], b""
    offset = 128 + 4 + 12 * len(tags)
    for sig, data in tags:
        while len(data) % 4:
            data += b"\0"
        table.append(struct.pack(">4sII", sig, offset + len(body), len(data)))
        body += data
    size = offset + len(body)
    header = bytearray(128)
    struct.pack_into(">I4sI4s4s4s", header, 0, size, b"none", 0x02400000, b"mntr", space, b"XYZ ")
    header[24:36] = struct.pack(">6H", 2026, 1, 1, 0, 0, 0)
    header[36:40] = b"acsp"
    header[68:80] = b"".join(_s15(c) for c in _D50)
    return bytes(header) + struct.pack(">I", len(tags)) + b"".join(table) + body


def rgb_profile(chromaticities, trc, description: str) -> bytes:
    """A matrix/TRC RGB display profile from primaries and white (x, y: red, green, blue,
    white), with one tone curve for all channels: a gamma, "srgb" or parametric type 3."""
    M, W = _rgb_to_xyz(chromaticities)
    A = _adapt_to_d50(W)
    cols = A @ M
    curve = _curve_tag(trc)
    return _assemble(b"RGB ", [
        (b"desc", _desc_tag(description)), (b"cprt", b"text\0\0\0\0public domain\0"),
        (b"wtpt", _xyz_tag(_D50)), (b"chad", b"sf32\0\0\0\0" + b"".join(_s15(v) for v in A.ravel())),
        (b"rXYZ", _xyz_tag(cols[:, 0])), (b"gXYZ", _xyz_tag(cols[:, 1])),
        (b"bXYZ", _xyz_tag(cols[:, 2])),
        (b"rTRC", curve), (b"gTRC", curve), (b"bTRC", curve)])


def grey_profile(gamma: float, description: str) -> bytes:
    """A grey display profile (D50 white) with a gamma tone curve."""
    return _assemble(b"GRAY", [
        (b"desc", _desc_tag(description)), (b"cprt", b"text\0\0\0\0public domain\0"),
        (b"wtpt", _xyz_tag(_D50)), (b"kTRC", _curve_tag(gamma))])


# ----------------------------------------------------------------------------- the transform

@dataclass
class ColourPlan:
    """What happens to one painting's colours; `record` goes into the manifest."""
    record: dict
    profile: bytes | None = None  # set when values are transformed
    channels: int = 3             # colour channels the profile takes (1 grey, 3 RGB, 4 CMYK)
    _lcms: object = field(default=None, repr=False)  # the core's IccTransform, made on first use

    @property
    def transforms(self) -> bool:
        return self.profile is not None

    def step(self) -> str:
        """The conversion string's colour step (empty when the values are not transformed)."""
        if not self.transforms:
            return ""
        r = self.record
        what = (r["profile"]["description"] if r["profile"] else "EXR chromaticities")
        if self.channels == 4:
            what = f"CMYK ({what}{', assumed: no embedded profile' if r['source_space'] == 'default CMYK profile' else ''})"
        return (f"colour {what} -> sRGB ({r['intent']}"
                f"{', BPC' if r['black_point_compensation'] else ''}; LittleCMS at 16 bits)")

    def apply(self, band: np.ndarray) -> np.ndarray:
        """(h, w, c) uint8 / uint16 / float -> (h, w, 3) uint16 sRGB. Extra channels (alpha)
        are dropped before the transform."""
        a = band[:, :, :self.channels] if band.ndim == 3 else band[:, :, None]
        if a.dtype.kind == "f":
            if np.isnan(a).any():
                raise ValueError("image contains NaN pixels")
            a = np.rint(np.clip(a, 0.0, 1.0) * 65535.0).astype(np.uint16)
        elif a.dtype not in (np.uint8, np.uint16):
            raise ValueError(f"unsupported pixel type {a.dtype.name}")
        return self._transform().apply(np.ascontiguousarray(a))

    def _transform(self):
        if self._lcms is None:
            from .. import _core
            self._lcms = _core.IccTransform(self.profile, self.record["intent"],
                                            self.record["black_point_compensation"])
        return self._lcms


def plan_colour(where: str, channels: int, icc: bytes | None = None,
                chromaticities=None, mode: str = "convert", intent: str = "relative",
                black_point_compensation: bool = True, cmyk: bool = False) -> ColourPlan:
    """Decides how an input's colours are stored: `channels` is the image's channel count,
    `icc` its embedded profile, `chromaticities` an EXR's attribute, `cmyk` whether its first
    four channels are C, M, Y, K (converted with its CMYK profile or, without one, the default
    CMYK profile; they cannot be kept). ValueError for an unknown mode or intent and for a
    profile that cannot be used."""
    if mode not in COLOUR_MODES:
        raise ValueError(f"unknown colour mode '{mode}' (expected convert or keep)")
    if intent not in INTENTS:
        raise ValueError(f"unknown rendering intent '{intent}' (expected perceptual, relative, "
                         "saturation or absolute)")
    colour_channels = 4 if cmyk else 1 if channels <= 2 else 3
    if cmyk and channels < 4:
        raise ValueError(f"{where}: a CMYK image needs 4 channels, it has {channels}")
    if cmyk and mode == "keep":
        raise ValueError(f"{where}: a CMYK image cannot be stored untouched (tiles are RGB); "
                         "use --colour convert (colour=\"convert\")")
    if cmyk and not (icc is not None and len(icc)):
        icc = default_cmyk_profile()
        if icc is None:
            raise ValueError(f"{where}: CMYK image without an embedded ICC profile, and no "
                             f"default CMYK profile is installed ({DEFAULT_CMYK_PROFILES[0]}, "
                             "Debian package libgs-common)")
        assumed = True
    else:
        assumed = False
    record = {"mode": mode, "source_space": "assumed sRGB", "profile": None,
              "intent": None, "black_point_compensation": False, "stored_space": "sRGB",
              "transform": "none"}
    profile, info = None, None
    if icc is not None and len(icc):
        info = parse_icc(icc, where)
        want = {"GRAY": 1, "RGB": 3, "CMYK": 4}[info.colour_space]
        if want != colour_channels:
            raise ValueError(f"{where}: the embedded {info.colour_space} ICC profile does not "
                             f"match the image's {channels} channel(s)")
        record.update(source_space="default CMYK profile" if assumed else "embedded ICC profile",
                      profile=info.record())
        profile = bytes(icc)[:info.size]
    elif chromaticities is not None:
        ch = tuple(float(c) for c in chromaticities)
        if len(ch) != 8 or not all(np.isfinite(ch)) or min(ch[1::2]) <= 0:
            raise ValueError(f"{where}: invalid chromaticities attribute {chromaticities}")
        record.update(source_space="EXR chromaticities", chromaticities=list(ch))
        if colour_channels == 3 and not np.allclose(ch, REC709_CHROMATICITIES, atol=1e-4):
            profile = rgb_profile(ch, 1.0, "EXR linear (chromaticities)")
    if mode == "keep":
        record.update(stored_space="source" if (info or profile) else "sRGB",
                      transform="none (values stored untouched)")
        return ColourPlan(record)
    if profile is None:
        return ColourPlan(record)
    from .. import _core
    record.update(intent=intent, black_point_compensation=bool(black_point_compensation),
                  transform=f"LittleCMS {_core.lcms_version()} (gigascroll core) to its built-in "
                            "sRGB IEC61966-2.1 at 16 bits, then rounded to 8 bits")
    plan = ColourPlan(record, profile, colour_channels)
    try:  # a profile LittleCMS cannot use fails here, before any tile is written
        plan.apply(np.zeros((1, 1, colour_channels), np.uint16))
    except ValueError as e:
        raise ValueError(f"{where}: ICC profile cannot be used: {e}") from None
    return plan

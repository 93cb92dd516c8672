"""The camera response of every image a person looks at: linear radiance -> exposure -> tone
curve -> sRGB. `render`'s PNG / JPEG, the `gallery` walk's frames and video, `view`, the
Mitsuba comparisons' PNGs and the browser client (scene.json's `display`, drawn by the GLSL
twin of this file in web/display.glsl.js) all go through `Display`; EXR and HDR outputs stay
linear radiance.

Exposure: a factor on radiance (W / m^2 / sr per channel), given three ways:

- EV100, the photographer's exposure value at ISO 100: the factor is 1 / L_max with
  L_max = 1.2 x 2^EV100 cd / m^2 the luminance that saturates the sensor (saturation-based
  sensitivity, ISO 12232; as in "Moving Frostbite to PBR", Lagarde and de Rousiers 2014),
  luminance being radiance x 683 lm / W (the rooms' lux-equivalent convention, room/builtin.py);
- `white=200lux`: a white painting (texel 255: albedo PAINTING_WHITE) lit by 200 lux is exposed
  to PAPER_WHITE = 0.8, the top of the range the neutral curve reproduces exactly, so every
  colour of a painting at that illuminance keeps its value on screen (less the curve's 0.04
  offset);
- `auto` (the default): `white=` the paintings' median direct illuminance, computed from the
  room's lights with Lambert's polygon formula (gallery/exposure.py).

Tone curves: "neutral" is the Khronos PBR Neutral tone mapper (Khronos Group, 2024: the
reference implementation's constants, startCompression = 0.8 - 0.04, desaturation = 0.15):
the identity less a small offset up to 0.8, then a compression of the peak channel towards 1
that keeps hue (every change lies in the plane of the colour and the white axis) and only
desaturates what it compresses. Chosen over ACES and AgX because those shift hues and contrast
at every level, even at normal exposure, and a painting's colours must stay true. "clip" is
the former response, clamp to [0, 1]. Both end in the sRGB transfer function (IEC 61966-2-1)
and round to nearest 8-bit code.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

__all__ = ["TONES", "PAPER_WHITE", "PAINTING_WHITE", "LUMENS_PER_WATT", "Display",
           "ExposureSetting", "pbr_neutral", "srgb_encode", "to_display", "to_srgb8",
           "exposure_of_ev100", "ev100_of_exposure", "exposure_for_white"]

TONES = ("neutral", "clip")
PAPER_WHITE = 0.8          # exposed value of a white painting at the reference illuminance
PAINTING_WHITE = 0.9       # albedo of a painting's white texel (gallery.PAINTING_REFLECTANCE)
LUMENS_PER_WATT = 683.0    # lux equivalent per W / m^2 per channel (room.builtin)
SATURATION_K = 1.2         # L_max = 1.2 x 2^EV100 cd / m^2 (78 / (100 x 0.65))

# Khronos PBR Neutral's constants (the reference pbrNeutral.glsl).
NEUTRAL_START = 0.8 - 0.04
NEUTRAL_DESATURATION = 0.15


def pbr_neutral(rgb, copy: bool = True) -> np.ndarray:
    """Khronos PBR Neutral of non-negative linear Rec. 709 colours (..., 3): linear output in
    [0, 1). The reference GLSL (PBRNeutralToneMapping) step by step, vectorised in float32 as
    a GPU computes it. copy=False works in place on a contiguous float32 array."""
    c = np.array(rgb, dtype=np.float32) if copy else rgb
    if not copy and not (isinstance(c, np.ndarray) and c.dtype == np.float32
                         and c.flags.c_contiguous and c.flags.writeable):
        raise ValueError("pbr_neutral(copy=False) needs a writeable C-contiguous float32 array")
    flat = c.reshape(-1, 3)
    r, g, b = flat[:, 0], flat[:, 1], flat[:, 2]
    x = np.minimum(np.minimum(r, g), b)
    offset = np.where(x < np.float32(0.08), x - np.float32(6.25) * x * x, np.float32(0.04))
    flat -= offset[:, None]
    peak = np.maximum(np.maximum(r, g), b)
    d, start, one = np.float32(1.0 - NEUTRAL_START), np.float32(NEUTRAL_START), np.float32(1.0)
    hot = peak >= start                                # `if (peak < start) return color;`
    p = np.maximum(peak, start)                        # (the others' values are not used)
    new_peak = one - d * d / (p + d - start)
    mix = one - one / (np.float32(NEUTRAL_DESATURATION) * (p - new_peak) + one)
    # mix(color * newPeak / peak, newPeak, g), per pixel: a scale and an offset
    flat *= np.where(hot, new_peak / p * (one - mix), one)[:, None]
    flat += np.where(hot, new_peak * mix, np.float32(0.0))[:, None]
    return c


def srgb_encode(linear) -> np.ndarray:
    """The sRGB transfer function of linear values in [0, 1]."""
    c = np.asarray(linear, dtype=np.float32)
    return np.where(c <= np.float32(0.0031308), np.float32(12.92) * c,
                    np.float32(1.055) * np.power(c, np.float32(1 / 2.4)) - np.float32(0.055))


def to_display(radiance, exposure: float = 1.0, tone: str = "neutral") -> np.ndarray:
    """Display-linear values in [0, 1] of linear radiance (..., 3) at `exposure` through the
    tone curve (NaN and negative radiance show as black)."""
    if tone not in TONES:
        raise ValueError(f"tone must be one of {', '.join(TONES)}, got {tone!r}")
    c = np.array(radiance, dtype=np.float32)
    np.nan_to_num(c, copy=False, nan=0.0, posinf=1e18, neginf=0.0)
    with np.errstate(over="ignore"):  # past float32's range: inf, clipped next
        c *= np.float32(exposure)
    # at most 1e18: the curve's squares stay finite in float32 (it is at 1 long before)
    c = np.clip(c, np.float32(0.0), np.float32(1e18), out=c)
    if tone == "neutral":
        c = pbr_neutral(c, copy=False)
    return np.minimum(c, np.float32(1.0), out=c)


def _code_tables(bins: int = 8192):
    """The 8-bit sRGB encoding as tables: THRESHOLDS[k], the display-linear value from which
    the code is k + 1 (sRGB(v) * 255 rounds up past k + 0.5; inf for k = 255), and BASE[i], the
    code at i / bins. A bin is narrower than a code (the curve's steepest slope is 3295 codes
    per unit, at 0), so a value's code is BASE[i] or the one after: one comparison."""
    y = (np.arange(255) + 0.5) / 255
    t = np.where(y <= 0.04045, y / 12.92, ((y + 0.055) / 1.055) ** 2.4)
    thresholds = np.append(t, np.inf).astype(np.float32)
    base = np.searchsorted(thresholds, np.arange(bins + 1) / bins, side="right").astype(np.uint8)
    return thresholds, base, bins


_THRESHOLDS, _BASE, _BINS = _code_tables()


def to_srgb8(radiance, exposure: float = 1.0, tone: str = "neutral") -> np.ndarray:
    """8-bit sRGB codes of linear radiance: to_display, then the sRGB curve rounded to
    nearest (int(sRGB(v) * 255 + 0.5), through _code_tables: the same codes as the formula
    up to float rounding at a code's edge, several times faster)."""
    v = to_display(radiance, exposure, tone)
    base = _BASE[(v * np.float32(_BINS)).astype(np.int32)]
    return base + (v >= _THRESHOLDS[base])


def exposure_of_ev100(ev100: float) -> float:
    """The factor on radiance of a camera at EV100: 683 / (1.2 x 2^EV100)."""
    return LUMENS_PER_WATT / (SATURATION_K * 2.0 ** float(ev100))


def ev100_of_exposure(exposure: float) -> float:
    """The EV100 whose factor is `exposure` (exposure_of_ev100's inverse)."""
    return math.log2(LUMENS_PER_WATT / (SATURATION_K * float(exposure)))


def exposure_for_white(lux: float) -> float:
    """The factor that exposes a white painting (albedo PAINTING_WHITE) under `lux` to
    PAPER_WHITE: its radiance is PAINTING_WHITE x (lux / 683) / pi."""
    return PAPER_WHITE * math.pi * LUMENS_PER_WATT / (PAINTING_WHITE * float(lux))


_WHITE = re.compile(r"white=([^a-z]*)(lux|lx)?", re.I)
MAX_LUX = 1e7             # far above daylight (1e5 lux): a typo, not a gallery
EV_RANGE = (-20.0, 40.0)  # moonless night is about -6, the sun's disc about 33


@dataclass(frozen=True)
class ExposureSetting:
    """An --exposure option: "auto", an EV100 number, or "white=LUXlux"."""

    mode: str = "auto"          # auto | ev100 | white
    value: float | None = None  # the EV100 or the lux

    @classmethod
    def parse(cls, text) -> "ExposureSetting":
        """ValueError (one line) for anything but auto, a finite EV100 in EV_RANGE or
        white=LUX[lux] with 0 < LUX <= MAX_LUX."""
        t = str(text).strip()
        if t.lower() == "auto":
            return cls()
        m = _WHITE.fullmatch(t)
        if m:
            lux = _number(m.group(1), t)
            if not 0 < lux <= MAX_LUX:
                raise ValueError(f"--exposure white=LUX wants 0 < LUX <= {MAX_LUX:g} lux, "
                                 f"got {t[:40]!r}")
            return cls("white", lux)
        ev = _number(t, t)
        if not EV_RANGE[0] <= ev <= EV_RANGE[1]:
            raise ValueError(f"--exposure EV100 must be in [{EV_RANGE[0]:g}, {EV_RANGE[1]:g}], "
                             f"got {t[:40]!r}")
        return cls("ev100", ev)

    def display(self, auto_lux: float, tone: str = "neutral", auto_how: str = "") -> "Display":
        """The Display of this setting; `auto_lux`: the reference illuminance of "auto"."""
        if self.mode == "ev100":
            return Display(exposure_of_ev100(self.value), tone, f"EV100 {self.value:g}")
        lux = self.value if self.mode == "white" else auto_lux
        how = f"white={lux:.4g}lux" + (f" (auto: {auto_how})" if self.mode == "auto" and auto_how
                                       else " (auto)" if self.mode == "auto" else "")
        return Display(exposure_for_white(lux), tone, how, lux)


def _number(text: str, whole: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"--exposure must be auto, an EV100 number or white=LUXlux (e.g. "
                         f"white=200lux), got {whole[:40]!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"--exposure must be finite, got {whole[:40]!r}")
    return x


@dataclass(frozen=True)
class Display:
    """One camera response: the factor on radiance, the tone curve, and how the factor was
    chosen (for reports); white_lux: the illuminance at which a white painting shows as
    PAPER_WHITE (None when set by EV100)."""

    exposure: float = 1.0
    tone: str = "neutral"
    how: str = ""
    white_lux: float | None = None

    def __post_init__(self):
        if self.tone not in TONES:
            raise ValueError(f"tone must be one of {', '.join(TONES)}, got {self.tone!r}")
        if not (math.isfinite(self.exposure) and self.exposure > 0):
            raise ValueError(f"exposure must be a positive number, got {self.exposure!r}")

    def srgb8(self, radiance) -> np.ndarray:
        return to_srgb8(radiance, self.exposure, self.tone)

    @property
    def ev100(self) -> float:
        return ev100_of_exposure(self.exposure)

    def describe(self) -> dict:
        """What a report states: exposure factor, EV100, tone, paper white and how chosen."""
        return {"exposure": self.exposure, "ev100": round(self.ev100, 4), "tone": self.tone,
                "paper_white": PAPER_WHITE, "white_lux": self.white_lux, "how": self.how}

    def scene_json(self) -> dict:
        """scene.json's display block: the factor and the client's mapping name."""
        return {"exposure": self.exposure, "tone": f"{self.tone}-srgb", "ev100": self.ev100}

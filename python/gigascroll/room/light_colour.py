"""A light's colour from its colour temperature, and the photometric weighting of the gallery's
linear sRGB channels.

`kelvin_to_rgb(T)`: the Planckian (blackbody) radiator at T kelvin, as the CIE defines the
colour of an incandescent-like source: its spectrum (Planck's law) integrated against the CIE
1931 2-degree colour-matching functions (the CIE's 1 nm table, shipped in data/) to XYZ, then
XYZ -> linear sRGB (IEC 61966-2-1's matrix: the Rec. 709 primaries and the D65 white point),
normalised to unit luminance
(`luminance(rgb) == 1`). So a light of radiance L x kelvin_to_rgb(T) has the same luminance,
and gives the same lux, whatever its colour temperature.

Why a shipped table and numpy rather than colour-science at run time: the computation is a
weighted sum over 471 wavelengths, and colour-science (a large package whose import takes a
second and warns without SciPy) stays a test-only dependency, the tests' independent reference.

Lux: the project's "lux equivalent" (room/builtin.py) is 683 lm / W times irradiance. For a
coloured light the photometric quantity is the luminance-weighted sum of the linear sRGB
channels, Y = 0.2126 R + 0.7152 G + 0.0722 B (the Y row of sRGB's RGB -> XYZ, IEC 61966-2-1),
times 683 lm / W; for a white light (equal channels) it is the channel value times 683, as
before.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np

__all__ = ["LUMINANCE_WEIGHTS", "KELVIN_RANGE", "luminance", "kelvin_to_rgb", "kelvin_to_xyz",
           "xyz_to_linear_srgb_matrix"]

# Y of linear sRGB (IEC 61966-2-1's rounded Y row): the photometric weighting of the channels.
LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)
# Below about 1900 K the Planckian locus leaves sRGB's gamut (blue < 0); beyond 25000 K no
# museum light goes.
KELVIN_RANGE = (2000.0, 25000.0)

_CMF_FILE = Path(__file__).resolve().parent / "data" / "cie1931_2deg_cmf.csv"
# Planck's second radiation constant c2 = h c / k as CIE 015:2018 fixes it for the Planckian
# radiator (the ITS-90 value), in m K.
_C2 = 1.4388e-2
# XYZ -> linear sRGB as IEC 61966-2-1 publishes it (Rec. 709 primaries, D65 white).
_XYZ_TO_SRGB = ((3.2406, -1.5372, -0.4986), (-0.9689, 1.8758, 0.0415), (0.0557, -0.2040, 1.0570))


def luminance(rgb) -> np.ndarray:
    """Y of linear sRGB values (..., 3): the photometric weighting (0.2126, 0.7152, 0.0722)."""
    return np.asarray(rgb, np.float64) @ np.asarray(LUMINANCE_WEIGHTS)


@functools.lru_cache(maxsize=1)
def _cmf() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths in nm (471,), x_bar y_bar z_bar (471, 3)) from the shipped CIE table."""
    table = np.loadtxt(_CMF_FILE, delimiter=",", comments="#", skiprows=5)
    return table[:, 0], table[:, 1:]


def xyz_to_linear_srgb_matrix() -> np.ndarray:
    """The 3 x 3 XYZ -> linear sRGB matrix of IEC 61966-2-1."""
    return np.array(_XYZ_TO_SRGB)


def _check_kelvin(kelvin) -> float:
    if isinstance(kelvin, bool) or not isinstance(kelvin, (int, float, np.integer, np.floating)):
        raise ValueError(f"colour temperature must be a number of kelvin, got {kelvin!r}")
    t = float(kelvin)
    lo, hi = KELVIN_RANGE
    if not (math.isfinite(t) and lo <= t <= hi):
        raise ValueError(f"colour temperature must be in [{lo:g}, {hi:g}] K (sRGB's gamut holds "
                         f"the Planckian locus there), got {kelvin!r}")
    return t


def kelvin_to_xyz(kelvin: float) -> np.ndarray:
    """CIE 1931 XYZ of the blackbody at `kelvin`, scaled to Y = 1."""
    t = _check_kelvin(kelvin)
    nm, cmf = _cmf()
    lam = nm * 1e-9
    # Planck's law up to a constant factor (it cancels in the normalisation).
    spectrum = lam ** -5 / np.expm1(_C2 / (lam * t))
    xyz = spectrum @ cmf
    return xyz / xyz[1]


def kelvin_to_rgb(kelvin: float) -> tuple[float, float, float]:
    """Linear sRGB of the blackbody at `kelvin` (in KELVIN_RANGE), at unit luminance
    (luminance(rgb) == 1). ValueError outside the range or for a non-number."""
    rgb = xyz_to_linear_srgb_matrix() @ kelvin_to_xyz(kelvin)
    rgb /= luminance(rgb)
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]))

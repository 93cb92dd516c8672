"""A light's colour temperature as linear sRGB (room/light_colour.py) against colour-science:
the blackbody's spectrum (colour.sd_blackbody) integrated against the CIE 1931 2-degree
observer that colour-science ships, XYZ to linear sRGB through its sRGB colourspace, both
scaled to unit luminance."""

import numpy as np
import pytest

from gigascroll.room.light_colour import KELVIN_RANGE, kelvin_to_rgb, luminance

colour = pytest.importorskip("colour")


def reference_rgb(kelvin: float) -> np.ndarray:
    shape = colour.SpectralShape(360, 830, 1)
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    xyz = colour.sd_to_XYZ(colour.sd_blackbody(kelvin, shape), cmfs,
                           illuminant=colour.sd_ones(shape), method="Integration")
    rgb = colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False)
    return rgb / (rgb @ [0.2126, 0.7152, 0.0722])


@pytest.mark.parametrize("kelvin", [2700, 3000, 4000, 5000, 6500])
def test_kelvin_to_rgb_is_colour_sciences_planckian_radiator(kelvin):
    # 1e-6: the shipped table's 7 significant digits (2e-7 measured at 2000 K, 4e-8 here)
    np.testing.assert_allclose(kelvin_to_rgb(kelvin), reference_rgb(kelvin), rtol=1e-6)


def test_unit_luminance_and_the_warm_to_cool_order():
    rgbs = np.array([kelvin_to_rgb(k) for k in (2000, 2700, 4000, 6500, 25000)])
    np.testing.assert_allclose(luminance(rgbs), 1.0, rtol=1e-12)
    assert np.all(np.diff(rgbs[:, 0]) < 0) and np.all(np.diff(rgbs[:, 2]) > 0)
    assert np.all(rgbs > 0)
    # D65 is not on the Planckian locus, but 6500 K is close to sRGB's white
    np.testing.assert_allclose(kelvin_to_rgb(6500), 1.0, atol=0.05)


@pytest.mark.parametrize("bad", [KELVIN_RANGE[0] - 1, KELVIN_RANGE[1] + 1, float("nan"),
                                 float("inf"), -3000, True, "3000", None])
def test_outside_the_range_is_a_value_error(bad):
    with pytest.raises(ValueError, match="colour temperature"):
        kelvin_to_rgb(bad)

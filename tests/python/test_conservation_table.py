"""The CIE 157:2004 table shipped in gallery/conservation.py, against the figures the
published readings of the standard give (named in the module's docstring): limiting
illuminance 50 lx for the high and medium categories and 200 lx for the low one, limiting
annual exposure 15 000, 150 000 and 600 000 lx h, no limit for irresponsive objects; and the
warnings fire exactly past those limits."""

from __future__ import annotations

import pytest

from gigascroll.gallery.conservation import (CATEGORIES, LIMITS, SOURCE, annual_exposure,
                                             check_exposure, limits_of)

PUBLISHED = {  # category: (CIE name, lx, lx h per year)
    "none": ("irresponsive", None, None),
    "low": ("low responsivity", 200, 600_000),
    "medium": ("medium responsivity", 50, 150_000),
    "high": ("high responsivity", 50, 15_000),
}


def test_the_table_is_cie_157s():
    assert CATEGORIES == ("none", "low", "medium", "high")
    for category, (name, lux, dose) in PUBLISHED.items():
        row = limits_of(category)
        assert (row.category, row.name, row.lux, row.lux_hours) == (category, name, lux, dose)
    assert SOURCE.startswith("CIE 157:2004")


@pytest.mark.parametrize("category", ["low", "medium", "high"])
def test_warnings_start_just_past_each_limit(category):
    row = LIMITS[category]
    assert check_exposure(row, row.lux, row.lux_hours) == []
    over = check_exposure(row, row.lux * 1.001, row.lux_hours * 1.001)
    assert len(over) == 2 and all("CIE 157:2004" in w for w in over)
    # 50 lx for 8 h a day, 300 days a year: 120 000 lx h, inside medium, 8x high's limit.
    dose = annual_exposure(50, 8, 300)
    assert dose == 120_000
    assert bool(check_exposure(row, 50, dose)) == (category == "high")


def test_unknown_category_names_the_known_ones():
    with pytest.raises(ValueError, match="none, low, medium, high"):
        limits_of("very high")

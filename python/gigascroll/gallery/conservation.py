"""How much light a museum object may receive: the responsivity categories of CIE 157:2004.

Source: CIE 157:2004, "Control of damage to museum objects by optical radiation" (Commission
Internationale de l'Eclairage, Vienna, 2004; ISBN 3 901 906 27 4), section 3.1.1 "Four
categories of responsivity" and the limits of section 3.2.1 "To minimise exposure of museum
objects": limiting illuminance and limiting annual exposure per category. The categories
are defined by the ISO blue wool lightfastness standards (ISO 105-B): high responsivity is
blue wool 1-3, medium 4-6, low 7-8 and above; irresponsive objects are made wholly of
materials light does not change (no limit; their illuminance is set by seeing alone).

The figures were checked against published readings of that table (the standard itself is
sold, not public): the four category names and section numbers from the report's table of
contents; the blue-wool definitions of the categories in S. Michalski, "Agent of
deterioration: light, ultraviolet and infrared" (Canadian Conservation Institute), which
states that CIE 2004 adopted them; 50 lx for the medium and high categories and no limit
for irresponsive objects, citing CIE 157:2004, in R. Schwen and R. Berns, "Design of LED
clusters for optimal museum lighting" (Rochester Institute of Technology, 2011), which
gives 150-200 lx for the low category (200 lx is CIE 157's limit, 150 lx CIBSE's advice);
and the annual exposures 600 000, 150 000 and 15 000 lx h for the low, medium and high
categories in the National Gallery London's Lux Allowance Calculator (J. Padfield, after
Thomson, "The Museum Environment", 1986, and Saunders, "Museum Lighting", Getty, 2020).
Ink and colours on silk and paper (the scrolls this project shows) are in the high or
medium category; conservators light such works at about 50 lux and count their yearly dose.

`LIMITS[category]`: its limiting illuminance in lux and limiting annual exposure in lux hours
per year; None is "no limit" (CIE 157's irresponsive category).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SOURCE", "CATEGORIES", "LIMITS", "CategoryLimits", "limits_of", "annual_exposure",
           "check_exposure"]

SOURCE = ('CIE 157:2004, "Control of damage to museum objects by optical radiation", '
          "Commission Internationale de l'Eclairage, Vienna, sections 3.1.1 and 3.2.1")


@dataclass(frozen=True)
class CategoryLimits:
    """One row of CIE 157:2004's table."""
    category: str          # the CLI's name: none, low, medium, high
    name: str              # the CIE's name
    lux: float | None      # limiting illuminance (lx); None: no limit
    lux_hours: float | None  # limiting annual exposure (lx h / year); None: no limit
    examples: str          # typical materials of the category (after CIE 157:2004)


LIMITS = {
    "none": CategoryLimits("none", "irresponsive", None, None,
                           "metal, stone, most glass, genuine ceramic, enamel, most minerals"),
    "low": CategoryLimits("low", "low responsivity", 200.0, 600_000.0,
                          "oil and tempera paintings, fresco, undyed leather and wood, horn, "
                          "bone, ivory, lacquer, some plastics"),
    "medium": CategoryLimits("medium", "medium responsivity", 50.0, 150_000.0,
                             "costumes, watercolours, pastels, tapestries, prints and drawings, "
                             "manuscripts, miniatures, distemper, wallpaper, gouache, dyed "
                             "leather, most natural history objects"),
    "high": CategoryLimits("high", "high responsivity", 50.0, 15_000.0,
                           "silk, colorants known to be highly fugitive (many inks, dyes and "
                           "lake pigments), newsprint, most felt-tip pens"),
}
CATEGORIES = tuple(LIMITS)


def limits_of(category: str) -> CategoryLimits:
    """The row of `category` (none, low, medium, high); ValueError for any other."""
    if not isinstance(category, str) or category not in LIMITS:
        raise ValueError(f"unknown responsivity category {category!r}; CIE 157:2004's are "
                         f"{', '.join(CATEGORIES)} (none = irresponsive)")
    return LIMITS[category]


def _hours(value, what: str, most: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{what} must be a number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and 0 <= v <= most):
        raise ValueError(f"{what} must be in [0, {most:g}], got {value!r}")
    return v


def annual_exposure(lux: float, hours_per_day: float, days_per_year: float) -> float:
    """Lux hours per year at a constant illuminance `lux` for these opening hours."""
    return (float(lux) * _hours(hours_per_day, "hours per day", 24)
            * _hours(days_per_year, "days per year", 366))


def check_exposure(limits: CategoryLimits, max_lux: float, lux_hours: float) -> list[str]:
    """The warnings for a painting whose brightest point receives `max_lux` and whose yearly
    dose (at that point) is `lux_hours`: one line per limit of the category exceeded."""
    warnings = []
    if limits.lux is not None and max_lux > limits.lux:
        warnings.append(f"illuminance up to {max_lux:.0f} lx exceeds the {limits.lux:.0f} lx "
                        f"limit for {limits.name} objects (CIE 157:2004)")
    if limits.lux_hours is not None and lux_hours > limits.lux_hours:
        warnings.append(f"annual exposure up to {lux_hours:,.0f} lx h exceeds the "
                        f"{limits.lux_hours:,.0f} lx h limit for {limits.name} objects "
                        f"(CIE 157:2004)")
    return warnings

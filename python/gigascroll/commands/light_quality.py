"""The light's one knob on the command line: `--quality draft|preview|final` or
`--light-budget SECONDS` (gallery/quality.py), shared by render --room, gallery, view, serve
and exhibit build."""

from __future__ import annotations

from ..errors import UserError


def add_light_quality_options(p, overrides: str = "") -> None:
    """--quality and --light-budget (mutually exclusive). `overrides`: the command's
    low-level light options that, when given, replace what the knob chose (for --help)."""
    from ..gallery.quality import DEFAULT_QUALITY, ERROR_TARGETS, QUALITY_LEVELS

    targets = ", ".join(f"{q} {100 * ERROR_TARGETS[q]:g}%%" for q in QUALITY_LEVELS)
    tail = f"; {overrides} given explicitly override what it chose" if overrides else ""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quality", choices=QUALITY_LEVELS, default=None,
                   help=f"the light's quality (default {DEFAULT_QUALITY}): photons, bake spacing, "
                        "emitter samples and final gather chosen for the room (docs/light.md, "
                        f"'One knob'); error targets, RMS on walls and floors: {targets}{tail}")
    g.add_argument("--light-budget", type=float, default=None, metavar="SECONDS",
                   help="instead of --quality: the finest settings whose predicted photon pass + "
                        f"bake time fits this many seconds{tail}")


def light_settings_of(args, spec):
    """The LightSettings of --quality / --light-budget for a RoomSpec (UserError if bad)."""
    from ..gallery.quality import light_settings

    try:
        return light_settings(spec, quality=getattr(args, "quality", None),
                              budget=getattr(args, "light_budget", None))
    except ValueError as e:
        raise UserError(f"--quality / --light-budget: {e}") from None


def check_light_budget(args) -> None:
    """Refuses a bad --light-budget before any work (UserError)."""
    from ..gallery.quality import check_budget

    if getattr(args, "light_budget", None) is not None:
        try:
            check_budget(args.light_budget)
        except ValueError as e:
            raise UserError(f"--light-budget: {e}") from None

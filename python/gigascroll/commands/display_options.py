"""--exposure and --tone: the camera response (display_mapping) of every command that writes or
shows an image (render, gallery, view, serve)."""

from __future__ import annotations

import argparse

from ..display_mapping import TONES, ExposureSetting

__all__ = ["add_display_options", "display_of"]


def _exposure(text: str) -> ExposureSetting:
    try:
        return ExposureSetting.parse(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("--exposure ")) from None


def add_display_options(p, linear_note: str = "EXR and HDR outputs stay linear radiance") -> None:
    p.add_argument("--exposure", type=_exposure, default=ExposureSetting(),
                   metavar="auto|EV100|white=LUXlux",
                   help="exposure of the images a person looks at: auto (default: a white "
                        "painting at the paintings' median direct illuminance shows as paper "
                        "white, 0.8), an EV100 number (e.g. 6), or white=200lux (a white "
                        f"painting at 200 lux shows as paper white); {linear_note}")
    p.add_argument("--tone", choices=TONES, default="neutral",
                   help="tone curve after the exposure: neutral (Khronos PBR Neutral: colours "
                        "true up to 0.8, highlights compressed without hue shifts; default) "
                        "or clip (clamp to 1)")


def display_of(args, room=None, lighting: str = "baked"):
    """The Display of the command's options for `room` (a RoomSpec; None: a built-in photon
    scene, whose radiance is in display units: auto is factor 1)."""
    from ..display_mapping import Display
    from ..gallery.exposure import room_display

    setting = args.exposure if isinstance(args.exposure, ExposureSetting) else \
        ExposureSetting.parse(args.exposure)
    if room is None and setting.mode == "auto":
        return Display(1.0, args.tone, "auto: the scene's radiance as is")
    return room_display(room, setting, args.tone, lighting)

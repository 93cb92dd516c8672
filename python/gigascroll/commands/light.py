"""`gigascroll light PACK --room scroll|hall|FILE [--lights FILE.json] [--category ...]
[--hours-per-day H --days-per-year D] [-o DIR]`, or `gigascroll light --exhibition SHOW`:
the illuminance on every painting as conservators use it: false-colour maps in lux, min /
mean / max and uniformity, the yearly dose in lux hours, and warnings against CIE 157:2004's
limits for the chosen responsivity category; written as index.html, light.json and one PNG
map per painting (default: next to the pack or show, PACK-light/ or SHOW-light/). A show's
paintings are named by their titles; its wall labels are not measured."""

from __future__ import annotations

import math
import os
from pathlib import Path

from ..errors import UserError
from .exhibition_options import require_pack_dir

COMMAND = "light"


def register(sub) -> None:
    p = sub.add_parser(
        "light", help="illuminance maps and lux figures of the paintings (CIE 157 limits)",
        description="Lights the room as the renders do (photon pass and bake) and computes the "
        "illuminance on a grid over every painting: false-colour maps in lux, min / mean / max "
        "and uniformity (min / mean), the yearly exposure in lux hours for the opening hours, "
        "and warnings where CIE 157:2004's limits for the chosen responsivity category are "
        "exceeded. Lux = 683 lm/W x (0.2126 R + 0.7152 G + 0.0722 B) of the irradiance "
        "(linear sRGB, W/m^2 per channel). Writes index.html, light.json and the maps.")
    p.add_argument("pack", metavar="PACK", nargs="?", default=None,
                   help="the tile pack whose paintings the room shows")
    from .exhibition_options import add_exhibition_option
    add_exhibition_option(p)
    p.add_argument("--room", default="scroll", help="scroll, hall, or a room file (glTF/OBJ/PLY)")
    p.add_argument("--lights", default=None, metavar="FILE.json",
                   help="light specs in place of the room's lights: a JSON list of {name, "
                        "centre, aim, width, height, [across] (or panels: a list of such "
                        "rectangles lit together), [kelvin], lumens | lux + painting}")
    p.add_argument("--category", default="high", choices=["high", "medium", "low", "none"],
                   help="CIE 157:2004 responsivity category whose limits apply (default high: "
                        "ink and colours on silk; none = irresponsive)")
    p.add_argument("--hours-per-day", type=float, default=8.0, metavar="H",
                   help="opening hours a day, lights on (default 8)")
    p.add_argument("--days-per-year", type=float, default=300.0, metavar="D",
                   help="opening days a year (default 300)")
    p.add_argument("--targets", choices=["direct", "total"], default="direct",
                   help="what a light's lux target on a painting means: its direct "
                        "illuminance, solved exactly (default), or the total with "
                        "interreflections, solved from one lighting pass per such light")
    p.add_argument("--lighting", choices=["baked", "full"], default="baked",
                   help="the baked irradiance the renders use (default), or direct light and "
                        "gather at every point")
    p.add_argument("--samples", type=int, default=256,
                   help="grid cells along each painting's longer side (2..4096, default 256)")
    p.add_argument("--photons", type=int, default=1 << 18,
                   help="photons for the lighting (default 262144)")
    p.add_argument("--light-samples", type=int, default=None, metavar="N",
                   help="emitter samples per point: the bake's (default 16) or, with "
                        "--lighting full, each grid point's (default 1024: min and max are "
                        "not to be made of noise)")
    p.add_argument("--bake-spacing", type=float, default=None, metavar="M",
                   help="bake lattice spacing in metres (default: the room's diagonal / 200)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    p.add_argument("-o", "--out", default=None,
                   help="report directory (default: next to the pack, PACK-light); an earlier "
                        "light report there is replaced")
    p.set_defaults(func=run)


def _check_args(args) -> None:
    from ..gallery.conservation import annual_exposure
    for name, value in (("--hours-per-day", args.hours_per_day),
                        ("--days-per-year", args.days_per_year)):
        if not math.isfinite(value):
            raise UserError(f"{name} must be a finite number, got {value}")
    try:
        annual_exposure(1.0, args.hours_per_day, args.days_per_year)
    except ValueError as e:
        raise UserError(f"--hours-per-day / --days-per-year: {e}") from None
    if not 2 <= args.samples <= 4096:
        raise UserError(f"--samples must be in [2, 4096], got {args.samples}")
    if args.light_samples is not None and not 1 <= args.light_samples <= 1 << 16:
        raise UserError(f"--light-samples must be in [1, 65536], got {args.light_samples}")
    if not 1 <= args.photons <= 1 << 26:
        raise UserError(f"--photons must be in [1, {1 << 26}], got {args.photons}")
    if args.bake_spacing is not None and not (math.isfinite(args.bake_spacing)
                                              and 1e-4 <= args.bake_spacing <= 100):
        raise UserError(f"--bake-spacing must be in [1e-4, 100] m, got {args.bake_spacing}")


def _room(args, pack):
    """The room spec, its lights replaced by --lights when given."""
    from ..room.lights import light_surface, load_lights
    from ..room.builtin import ROOM_NAMES, builtin_room
    from .gallery import load_room
    lights = load_lights(args.lights) if args.lights else None
    if args.room in ROOM_NAMES:
        room = builtin_room(args.room, pack, lights=lights)
    else:
        room = load_room(args.room, pack)
        if lights is not None:  # the file's emitters stay as surfaces, dark
            for s in room.surfaces:
                s.emission = (0.0, 0.0, 0.0)
            room.surfaces += [light_surface(light, room.paintings) for light in lights]
            room.lights = lights
    names = [s.name for s in room.surfaces]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise UserError(f"--lights: the light names {', '.join(map(repr, clash[:5]))} are "
                        "given twice or name a surface of the room; name each light once")
    return room


def _light_entry(light) -> dict:
    if light.lux is not None:
        where = (f" on painting {light.painting!r}" if light.painting is not None
                 else " at given points")
        kind = "total" if "total_scale" in light.details else "direct"
        target = f", solved for {light.lux:g} lx mean {kind} illuminance{where}"
    else:
        target = ""
    return {"name": light.name, "kelvin": light.kelvin,
            "colour": f"{light.kelvin:g} K" if light.kelvin is not None else "white (sRGB D65)",
            "lumens": light.details.get("lumens"), "radiance": light.details.get("radiance"),
            "rgb": light.details.get("rgb"), "target_lux": light.lux, "target": target,
            "panels": len(light.panels)}


def _lit(args, pack, room):
    """(gallery, vt): the room lit as the renders light it (photon pass, and bake)."""
    from ..gallery import Gallery
    from ..runtime import VirtualTexture

    gallery = Gallery.from_room(room, pack)
    vt = VirtualTexture(pack, (8, 8))  # albedo is not read: irradiance only
    samples = args.light_samples or (16 if args.lighting == "baked" else 1024)
    gallery.light(vt, photons=args.photons, threads=args.threads, light_samples=samples)
    if args.lighting == "baked":
        gallery.bake(spacing=args.bake_spacing, threads=args.threads, light_samples=samples)
    return gallery, vt


def _measured(room, show) -> list[int]:
    """The slots measured: all of a room's; a show's paintings, not its wall labels."""
    labels = {f"label-{p.name}" for p in show.exhibition.paintings} if show else set()
    return [i for i, s in enumerate(room.paintings) if s.name not in labels]


def _lux_grids(args, pack, room, show=None) -> tuple[list, dict]:
    """Every measured painting's lux grid, and the lighting's stats."""
    from ..gallery.illuminance import painting_lux
    gallery, vt = _lit(args, pack, room)
    grids = [painting_lux(gallery, vt, i, args.samples, args.lighting, args.threads)[0]
             for i in _measured(room, show)]
    return grids, {k: v for k, v in gallery.stats.items() if k != "albedo_levels"}


def _solve_total(args, pack, room, show=None) -> dict:
    """--targets total: the painting-targeted lights rescaled to meet their targets in total
    illuminance (gallery/light_solve.py)."""
    import numpy as np

    from ..gallery.light_solve import solve_total_targets

    def measure(r):
        grids, _ = _lux_grids(args, pack, r, show)
        return {i: float(np.nanmean(g)) if np.isfinite(g).any() else 0.0
                for i, g in zip(_measured(r, show), grids)}
    return solve_total_targets(room, measure)


def _measure(args, pack, room, show=None) -> tuple[dict, dict]:
    """Lights the room, computes every painting's lux and figures: (results, maps)."""
    import numpy as np

    from ..gallery.conservation import SOURCE, annual_exposure, limits_of
    from ..gallery.illuminance import direct_lux, painting_figures
    from ..gallery.light_report import map_png

    limits = limits_of(args.category)
    solve = _solve_total(args, pack, room, show) if args.targets == "total" else None
    grids, stats = _lux_grids(args, pack, room, show)
    titles = {p.name: p.title for p in show.exhibition.paintings} if show else {}
    paintings = []
    for i, lux in zip(_measured(room, show), grids):
        slot = room.paintings[i]
        f = painting_figures(lux, limits, args.hours_per_day, args.days_per_year)
        direct = direct_lux(room, i, args.samples)
        f["direct_mean_lux_analytic"] = None if direct is None else float(direct.mean())
        paintings.append({"slot": i, "name": titles.get(slot.name, slot.name or f"slot {i}"),
                          "width_m": float(slot.width_m), "height_m": float(slot.height_m),
                          "grid": [int(lux.shape[1]), int(lux.shape[0])], **f,
                          "map": f"map{i:03d}.png"})
    finite = [float(np.nanmax(g)) for g in grids if np.isfinite(g).any()]
    vmax = max(finite + [limits.lux or 0.0, 1.0])
    maps = {}
    for p, lux in zip(paintings, grids):
        title = (f"{p['name']}: min {p['min_lux'] or 0:.1f}, mean {p['mean_lux'] or 0:.1f}, "
                 f"max {p['max_lux'] or 0:.1f} lx")
        maps[p["map"]] = map_png(lux, p["width_m"], p["height_m"], title, vmax, limits.lux)
    results = {
        "room": room.name, "lighting": args.lighting,
        "pack": os.path.abspath(show.pack_path if show else args.pack),
        **({"exhibition": os.path.abspath(show.path)} if show else {}),
        "units": {"illuminance": "lx", "exposure": "lx h per year"},
        "lux_conversion": "683 lm/W x (0.2126 R + 0.7152 G + 0.0722 B) of the irradiance "
                          "(linear sRGB, W/m^2 per channel)",
        "grid_note": f"the cell centres of a grid of {args.samples} cells along its longer side",
        "category": {"category": limits.category, "name": limits.name, "lux": limits.lux,
                     "lux_hours": limits.lux_hours, "examples": limits.examples},
        "source": SOURCE, "hours_per_day": args.hours_per_day,
        "days_per_year": args.days_per_year,
        "hours_per_year": annual_exposure(1.0, args.hours_per_day, args.days_per_year),
        "lights": [_light_entry(light) for light in room.lights],
        "targets": args.targets, "total_solve": solve,
        "paintings": paintings, "stats": stats,
    }
    return results, maps


def run(args) -> int:
    from ..gallery.light_report import write_report
    from ..outputs import (beside, check_output, owned_by, refuse_input, replace_dir,
                           signals_interrupt, temp_dir, write_mark)
    from ..pack import TilePack

    from .exhibition_options import open_exhibition
    _check_args(args)
    show = open_exhibition(args, room_default="scroll")
    if show is not None and args.lights:
        raise UserError("--exhibition brings its own lights (the exhibition file's [[lights]]): "
                        "give --exhibition or --lights, not both")
    if show is None and args.pack is None:
        raise UserError("give a PACK (with --room) or --exhibition SHOW")
    p = Path(args.exhibition) if show is not None else require_pack_dir(args.pack)
    out = Path(args.out) if args.out is not None else beside(p, "light")
    try:
        if show is None:  # a report inside the pack would change the pack
            refuse_input(out, p, "the pack being lit")
        check_output(out, force=True, directory=True, owned=owned_by(COMMAND),
                     what="a light report")
    except OSError as e:
        raise UserError(f"--out {e}") from None
    pack = show.pack if show is not None else TilePack(p)
    room = show.room if show is not None else _room(args, pack)
    results, maps = _measure(args, pack, room, show)
    with signals_interrupt():
        tmp = temp_dir(out, hidden=True)
        try:
            write_report(tmp, results, maps)
            write_mark(tmp, COMMAND)
            replace_dir(tmp, out, owned=owned_by(COMMAND))
        except BaseException:
            import shutil
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    for q in results["paintings"]:
        line = (f"{q['name']}: min {q['min_lux'] or 0:.1f} lx, mean {q['mean_lux'] or 0:.1f} lx, "
                f"max {q['max_lux'] or 0:.1f} lx, uniformity {q['uniformity'] or 0:.2f}, "
                f"{q['annual_lux_hours_max'] or 0:,.0f} lx h a year at the brightest point")
        print(line + "".join(f"\n  warning: {w}" for w in q["warnings"]))
    print(f"wrote {os.path.abspath(out)}/ (index.html, light.json, {len(maps)} maps)")
    return 0

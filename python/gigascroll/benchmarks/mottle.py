"""`gigascroll bench mottle`: the mottle of the baked light against Mitsuba 3 (issue 40).

For each room (`scroll`, `hall`, and the example glTF room of room.example) with
paintings of one flat colour (so that relative radiance error is relative irradiance error):
a high-spp Mitsuba 3 reference (cached, keyed as `bench gallery`'s), then our baked still at
each configuration (photons x bake spacing x bake light samples x gather radius x sphere or
disc x gather stride x bake(fill_covered) x bake(indirect_filter); the defaults are those of
`Gallery.light` / `Gallery.bake`), measured by gallery.mottle: RMS relative error of the
blurred luminance on walls, floor, ceiling, paintings and other surfaces separately. Times:
photon pass + map (light) and bake, with Mitsuba's time for --timing-spp spp of the same
view in the same run beside them (the machine may be loaded: compare ratios). Writes
results.json and error_vs_bake.png to --out.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import pyplot, save_figure, write_json
from .gallery import _ints

ROOMS = ("scroll", "hall", "hall_table", "example")
# The flat paintings' colour (sRGB8): a light warm grey, albedo about 0.5.
FLAT_RGB = (200, 196, 188)


def add_arguments(parser) -> None:
    parser.add_argument("--rooms", default="scroll,hall,hall_table,example",
                        help="comma-separated: scroll, hall, hall_table (the hall seen from above a "
                             "table's paintings), example (default: all)")
    parser.add_argument("--width", type=int, default=128, help="still width (default 128)")
    parser.add_argument("--height", type=int, default=72, help="still height (default 72)")
    parser.add_argument("--supersample", type=int, default=3,
                        help="rays per pixel per axis of our stills (Mitsuba's box filter; default 3)")
    parser.add_argument("--sigma", type=float, default=2.0,
                        help="the blur's standard deviation in pixels (default 2)")
    parser.add_argument("--photons", default="19",
                        help="log2 photons, comma-separated (default 19: Gallery.light's default)")
    parser.add_argument("--spacings", default="200",
                        help="bake spacings as fractions 1/N of the room's diagonal (default 200: the default)")
    parser.add_argument("--bake-samples", default="16", help="bake emitter samples (default 16: the default)")
    parser.add_argument("--radius-factors", default="1",
                        help="gather radii as multiples of the automatic one, comma-separated (default 1)")
    parser.add_argument("--disc", default="0",
                        help="gather over the sphere (0) and/or the surface disc (1), comma-separated (default 0)")
    parser.add_argument("--gather-strides", default="2", help="bake gather strides (default 2: the default)")
    parser.add_argument("--indirect-filters", default="0",
                        help="bake(indirect_filter=...) values, comma-separated (default 0: the default)")
    parser.add_argument("--final-gathers", default="36",
                        help="bake(final_gather=...) rays per point, comma-separated (default 36: the default)")
    parser.add_argument("--sparse", default="1",
                        help="bake(sparse_final_gather=...): 0 and/or 1, comma-separated (default 1: the "
                             "default; 1 counts only with a gather stride above 1)")
    parser.add_argument("--quality", default="",
                        help="comma-separated quality levels (draft, preview, final): measure the knob's "
                             "settings for each room (gallery/quality.py) instead of the grid of the options above")
    parser.add_argument("--hot-spots", default="8",
                        help="bake(hot_spots=...) factors, comma-separated (default 8: the default; 0 off)")
    parser.add_argument("--fill-covered", default="1",
                        help="bake(fill_covered=...): 1 and/or 0, comma-separated (default 1)")
    parser.add_argument("--timing-rounds", type=int, default=0,
                        help="re-time every configuration's light + bake this many rounds, alternated, and "
                             "report medians (of light + bake and of the bake alone) and their ratios to the "
                             "first configuration's (default 0: off)")
    parser.add_argument("--reference-spp", type=int, default=4096, help="Mitsuba reference spp (default 4096)")
    parser.add_argument("--timing-spp", type=int, default=16,
                        help="Mitsuba spp timed in the same run, for time ratios (default 16)")
    parser.add_argument("--reference-cache", default="build/gallery-reference",
                        help="directory where the reference images are kept between runs")
    parser.add_argument("--out", default="bench/mottle", help="directory for results.json and the plot")


def flat_pack(directory: Path, sizes: dict):
    """A pack of paintings of one flat colour, {name: (width, height)}."""
    from .. import build_pack

    images = [np.broadcast_to(np.array(FLAT_RGB, np.uint8), (h, w, 3)).copy() for w, h in sizes.values()]
    return build_pack(images, Path(directory) / "flat.pack", tile_size=128, border=4, names=list(sizes),
                      force=True)


def room_and_pack(name: str, scratch: Path):
    """The room's spec and its flat pack: the bench gallery's painting sizes for scroll and
    hall, the example room's own for the glTF room."""
    from ..gallery import builtin_room
    from ..room.example import EXAMPLE_PAINTINGS, write_example_room
    from ..room.files import load_room

    if name == "example":
        pack = flat_pack(scratch / "example", EXAMPLE_PAINTINGS)
        glb = write_example_room(scratch / "example_room.glb")
        return load_room(glb, pack), pack
    sizes = {"scroll": (8192, 342)} | {f"painting{s}": (2048, 1536) for s in range(1, 8)}
    if name == "scroll":
        sizes = {"scroll": sizes["scroll"]}
    pack = flat_pack(scratch / name, sizes)
    return builtin_room(name.split("_")[0], pack), pack


def camera(gal, name: str, resolution):
    """The room's suggested view; hall_table: 0.6 m above the table, 0.5 m beyond the second
    painting's near edge, looking at its corner (the table between paintings, where the
    stair-stepped band showed)."""
    if name != "hall_table":
        return gal.camera(resolution, fov=60.0)
    s = gal.spec.paintings[1]
    o, u, v = (np.array(x, np.float64) for x in (s.origin, s.u_axis, s.v_axis))
    corner = o + 0.8 * s.width_m * u + s.height_m * v
    eye = corner + np.array([0.0, 0.6, 0.5])
    return gal.camera(resolution, fov=35.0, eye=tuple(eye), target=tuple(corner))


def measure_room(mi, name: str, args, scratch: Path, configs: list[tuple]) -> dict:
    """One room: its reference, Mitsuba's timing run, and each configuration's mottle."""
    from .. import VirtualTexture
    from ..gallery import Gallery
    from ..gallery.accuracy import image_errors
    from ..gallery.mottle import pool_segments, surface_segments
    from ..gallery.mottle import mottle as measure
    from .gallery import _mitsuba, cached_reference

    spec, pack = room_and_pack(name, scratch)
    gal = Gallery.from_room(spec, pack)
    vt = VirtualTexture(pack, (48, 48))
    k = args.supersample
    cam = camera(gal, name, (args.width * k, args.height * k))
    gal.stream(cam, vt)
    mcam = camera(gal, name, (args.width, args.height))
    ref, ref_seconds = cached_reference(mi, gal, mcam, args.reference_spp, Path(args.reference_cache))
    _, mitsuba_seconds = _mitsuba(mi, mi.load_dict(gal.to_mitsuba_dict(mcam)), args.timing_spp, seed=1)
    diag = math.dist(*gal.bounds)
    r = {"triangles": gal.triangle_count, "paintings": gal.painting_count, "diagonal_m": diag,
         "reference": {"spp": args.reference_spp, "seconds": ref_seconds},
         "mitsuba_timing": {"spp": args.timing_spp, "seconds": mitsuba_seconds}, "configs": []}
    segments = None
    auto_radius = {}
    resolved = []
    for cf in configs:
        if cf["quality"]:
            cf = knob_config(spec, diag, cf["quality"])
        photons, n, samples = cf["photons"], cf["diagonal_over"], cf["bake_samples"]
        if photons not in auto_radius:
            auto_radius[photons] = gal.light(vt, photons=1 << photons)["radius"]
        radius = None if cf["radius_factor"] == 1 else cf["radius_factor"] * auto_radius[photons]
        cf = {**cf, "radius": radius, "spacing": cf.get("spacing", diag / n)}
        resolved.append(cf)
        t0, t1, t2, st, bst = _light_and_bake(gal, vt, cf)
        img, hits = gal.render_display(cam, vt, lighting="baked", hits=True)
        if segments is None:
            segments, seg_class = surface_segments(spec, hits["position"], hits["slot"])
            segments = pool_segments(segments, k)
            r["pixel_m"] = _pixel_size(hits["position"], cam, k)
        img = img.reshape(args.height, k, args.width, k, 3).mean(axis=(1, 3))
        c = {"photons_log2": photons, "diagonal_over": n, "spacing_m": bst["spacing"], "bake_samples": samples,
             "radius_factor": cf["radius_factor"], "disc": cf["disc"], "gather_stride": cf["gather_stride"],
             "fill_covered": cf["fill_covered"], "indirect_filter": cf["indirect_filter"], "final_gather": cf["final_gather"], "sparse": cf["sparse"], "quality": cf["quality"], "hot_spots": cf["hot_spots"], "hot_points": bst["bake_hot_points"], "points_covered": bst["bake_points_covered"],
             "radius_m": st["radius"], "light_seconds": t1 - t0, "bake_seconds": t2 - t1,
             "bake_points": bst["bake_points"],
             "light_and_bake_over_mitsuba": (t2 - t0) / mitsuba_seconds,
             "mottle": measure(img, ref, segments, seg_class, args.sigma), **image_errors(img, ref)}
        r["configs"].append(c)
    if args.timing_rounds:
        # light + bake re-timed in rounds, the configurations in turn (every other round in
        # reverse), so that the machine's load falls on all alike; medians, and each over the
        # first configuration's.
        times = [[] for _ in resolved]  # (light + bake, bake) per round
        for rnd in range(args.timing_rounds):
            order = list(range(len(resolved)))
            for i in (order if rnd % 2 == 0 else order[::-1]):
                t0, t1, t2, _, _ = _light_and_bake(gal, vt, resolved[i])
                times[i].append((t2 - t0, t2 - t1))
        first = np.median(np.array(times[0]), axis=0)
        for c, t in zip(r["configs"], times):
            both, bake = np.median(np.array(t), axis=0)
            c["light_and_bake_median_s"], c["bake_median_s"] = float(both), float(bake)
            c["light_and_bake_over_first"], c["bake_over_first"] = float(both / first[0]), float(bake / first[1])
            c["light_and_bake_rounds"] = [a for a, _ in t]
    return r


def _light_and_bake(gal, vt, cf: dict):
    """Gallery.light then bake at one configuration: (t0, t1, t2, light stats, bake stats)."""
    t0 = time.perf_counter()
    st = gal.light(vt, photons=1 << cf["photons"], radius=cf["radius"], disc=cf["disc"])
    t1 = time.perf_counter()
    bst = gal.bake(spacing=cf["spacing"], light_samples=cf["bake_samples"], gather_stride=cf["gather_stride"],
                   fill_covered=cf["fill_covered"], indirect_filter=cf["indirect_filter"],
                   final_gather=cf["final_gather"], hot_spots=cf["hot_spots"], sparse_final_gather=cf["sparse"])
    return t0, t1, time.perf_counter(), st, bst


def knob_config(spec, diag: float, level: str) -> dict:
    """The quality knob's settings for this room at `level`, as one configuration of the grid
    (the bake's other settings its defaults, read from Gallery.bake's signature)."""
    import inspect

    from ..gallery import Gallery
    from ..gallery.quality import light_settings

    ls = light_settings(spec, quality=level)
    bake = {k: v.default for k, v in inspect.signature(Gallery.bake).parameters.items()}
    return dict(photons=int(math.log2(ls.photons)), diagonal_over=round(diag / ls.spacing),
                bake_samples=ls.light_samples, radius_factor=1.0, disc=False, gather_stride=ls.gather_stride,
                fill_covered=bake["fill_covered"], indirect_filter=bake["indirect_filter"],
                final_gather=ls.final_gather, hot_spots=bake["hot_spots"], sparse=ls.sparse_final_gather,
                quality=level, spacing=ls.spacing)


def _pixel_size(position: np.ndarray, cam, k: int) -> float:
    """The median footprint of one output pixel on the surfaces seen (metres)."""
    dist = np.linalg.norm(position.reshape(-1, 3) - np.asarray(cam.position), axis=1)
    dist = dist[np.isfinite(dist)]
    return float(np.median(dist) * 2 * math.tan(math.radians(cam.fov) / 2) / (cam.height / k))


def plot(results: dict, path: Path) -> None:
    """RMS mottle against light + bake time (over Mitsuba's timing run; the alternated median
    where --timing-rounds gave one): colour per room, marker per surface kind, one point per
    configuration (the photon counts below the largest hollow)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    for room_index, (name, r) in enumerate(results["rooms"].items()):
        colour = f"C{room_index}"
        mitsuba = r["mitsuba_timing"]["seconds"]
        most = max(c["photons_log2"] for c in r["configs"])
        for photons in sorted({c["photons_log2"] for c in r["configs"]}):
            same = [c for c in r["configs"] if c["photons_log2"] == photons]
            for cl, marker in (("walls", "o"), ("floor", "s"), ("paintings", "^"), ("other", "x")):
                pts = sorted((c.get("light_and_bake_median_s", c["light_seconds"] + c["bake_seconds"]) / mitsuba,
                              c["mottle"][cl]["rms"]) for c in same if c["mottle"].get(cl))
                if pts:
                    x, y = zip(*pts)
                    ax.plot(x, np.array(y) * 100, marker=marker, color=colour, ls="none",
                            mfc=colour if photons == most else "none", label=f"{name} {cl}, 2^{photons}")
    ax.axhline(1.0, color="grey", ls="--", lw=0.8)
    ax.axhline(0.5, color="grey", ls=":", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"light + bake time / Mitsuba {results['settings']['timing_spp']} spp (same run)")
    ax.set_ylabel("RMS relative error after blur (%)")
    ax.legend(fontsize=5.5, ncol=3)
    save_figure(fig, path)


def run(args) -> int:
    rooms = [r for r in args.rooms.split(",") if r]
    for r in rooms:
        if r not in ROOMS:
            raise UserError(f"unknown room {r!r} (measured: {', '.join(ROOMS)})")
    if not 0 <= args.timing_rounds <= 1000:
        raise UserError(f"--timing-rounds must be in [0, 1000], got {args.timing_rounds}")
    if min(args.width, args.height, args.supersample, args.reference_spp, args.timing_spp) < 1:
        raise UserError("--width, --height, --supersample, --reference-spp and --timing-spp must be >= 1")
    if not (math.isfinite(args.sigma) and 0.3 <= args.sigma <= 16):
        raise UserError(f"--sigma must be in [0.3, 16] pixels, got {args.sigma}")
    photons = _ints(args.photons, "--photons")
    if max(photons) > 26:
        raise UserError("--photons are powers of two up to 2^26")
    try:
        factors = [float(x) for x in args.radius_factors.split(",") if x]
    except ValueError:
        raise UserError(f"--radius-factors are numbers, got {args.radius_factors!r}") from None
    if not factors or not all(0 < f <= 16 for f in factors):
        raise UserError(f"--radius-factors are multiples in (0, 16], got {args.radius_factors!r}")
    flags = {}
    for what in ("disc", "fill_covered", "sparse"):
        text = getattr(args, what)
        if not set(text.split(",")) <= {"0", "1"}:
            raise UserError(f"--{what.replace('_', '-')} takes 0 and/or 1, got {text!r}")
        flags[what] = [x == "1" for x in text.split(",")]
    try:
        filters = [float(x) for x in args.indirect_filters.split(",") if x]
    except ValueError:
        raise UserError(f"--indirect-filters are numbers, got {args.indirect_filters!r}") from None
    if not filters or not all(0 <= f <= 16 for f in filters):
        raise UserError(f"--indirect-filters are in [0, 16], got {args.indirect_filters!r}")
    try:
        gathers = [int(x) for x in args.final_gathers.split(",") if x]
    except ValueError:
        raise UserError(f"--final-gathers are integers, got {args.final_gathers!r}") from None
    if not gathers or min(gathers) < 0 or max(gathers) > 4096:
        raise UserError(f"--final-gathers are rays in [0, 4096], got {args.final_gathers!r}")
    try:
        hots = [float(x) for x in args.hot_spots.split(",") if x]
    except ValueError:
        raise UserError(f"--hot-spots are numbers, got {args.hot_spots!r}") from None
    if not hots or not all(h == 0 or 1 <= h <= 1e6 for h in hots):
        raise UserError(f"--hot-spots are 0 or in [1, 1e6], got {args.hot_spots!r}")
    strides = _ints(args.gather_strides, "--gather-strides")
    if not set(strides) <= {1, 2, 4, 8}:
        raise UserError("--gather-strides takes 1, 2, 4, 8")
    configs = [dict(photons=p, diagonal_over=n, bake_samples=s, radius_factor=f, disc=d, gather_stride=st,
                    fill_covered=fc, indirect_filter=fi, final_gather=fg, hot_spots=h, sparse=sp, quality=None)
               for p in photons for n in _ints(args.spacings, "--spacings")
               for s in _ints(args.bake_samples, "--bake-samples") for f in factors for d in flags["disc"]
               for st in strides for fc in flags["fill_covered"] for fi in filters
               for fg in gathers for h in hots for sp in (flags["sparse"] if st > 1 and fg > 0 else [False])]
    if args.quality:
        from ..gallery.quality import check_quality

        try:
            configs = [dict(quality=check_quality(q)) for q in args.quality.split(",")]
        except ValueError as e:
            raise UserError(str(e)) from None
    try:
        import mitsuba as mi
    except ImportError:
        raise UserError("the mottle benchmark needs mitsuba (pip install mitsuba)") from None
    mi.set_variant("scalar_rgb")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = {"settings": {k: getattr(args, k) for k in (
        "width", "height", "supersample", "sigma", "photons", "spacings", "bake_samples", "radius_factors", "disc",
        "gather_strides", "fill_covered", "indirect_filters", "final_gathers", "hot_spots", "sparse", "quality",
        "timing_rounds", "reference_spp", "timing_spp")}, "load_average": os.getloadavg(), "rooms": {}}
    with tempfile.TemporaryDirectory(prefix="gigascroll-bench-mottle-") as scratch:
        for name in rooms:
            results["rooms"][name] = measure_room(mi, name, args, Path(scratch), configs)
            _print_room(name, results["rooms"][name])
    results["load_average_after"] = os.getloadavg()
    write_json(out / "results.json", results)
    plot(results, out / "error_vs_bake.png")
    print(f"wrote {out / 'results.json'}")
    return 0


def _print_room(name: str, r: dict) -> None:
    for c in r["configs"]:
        parts = [f"{cl} {c['mottle'][cl]['rms'] * 100:.2f}%" for cl in ("walls", "floor", "paintings", "other")
                 if c["mottle"].get(cl)]
        print(f"{name}: 2^{c['photons_log2']} photons, r x {c['radius_factor']:g}{' disc' if c['disc'] else ''}, "
              f"diag/{c['diagonal_over']}, {c['bake_samples']} samples, stride {c['gather_stride']}, "
              f"fill {int(c['fill_covered'])}, filter {c['indirect_filter']:g}, final gather {c['final_gather']}"
              f"{' sparse' if c.get('sparse') else ''}, hot {c['hot_spots']:g} ({c['hot_points']})"
              f"{' = ' + c['quality'] if c.get('quality') else ''}: "
              f"{', '.join(parts)}; light+bake {c['light_seconds'] + c['bake_seconds']:.2f} s "
              f"({c['light_and_bake_over_mitsuba']:.2f}x Mitsuba {r['mitsuba_timing']['spp']} spp)"
              + (f"; median of {len(c['light_and_bake_rounds'])} {c['light_and_bake_median_s']:.3f} s = "
                 f"{c['light_and_bake_over_first']:.2f}x the first (the bake alone {c['bake_median_s']:.3f} s = "
                 f"{c['bake_over_first']:.2f}x)" if "light_and_bake_median_s" in c else ""))

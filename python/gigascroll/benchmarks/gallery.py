"""`gigascroll bench gallery`: the built-in `scroll` and `hall` rooms with a pack of smooth
synthetic paintings. For each room: Mitsuba 3's path tracer on a spp ladder against a
high-spp reference (computed once and cached), and a grid of our baked-still configurations
(photons x gather (the sphere, or the surface disc at multiples of the auto radius) x final gather x bake
spacing x bake light samples x gather stride x rays per pixel), each timed end to end: photon pass + photon
map build + bake + the still itself. The error-time Pareto front of those configurations is
compared with Mitsuba's time to the same error (log-log interpolation along its ladder), on
the same cores. At the default settings, the error that baking adds over full lighting.

Our stills cast --supersample^2 rays per pixel (pixel centres of a finer grid, box-filtered)
because Mitsuba's box pixel filter averages over the pixel; times are for that many rays.
The grid's configurations are each timed once (on a shared machine, noisy): that chooses
the fastest configuration per target error. Choosing the fastest of many single timings
favours lucky ones, so the chosen configurations and the Mitsuba ladder points the targets
use are then re-timed --timing-repeats times (--cheap-repeats times for jobs of at most 50 ms,
whose times scatter most), interleaved (ours and Mitsuba's alternating, the order reversed
every other round), and the speedups are ratios of those medians, with the spread of the
repeats beside them.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import pyplot, save_figure, write_json
from ..gallery.quality import STEPS

ROOMS = ("scroll", "hall")
from .ladder_timing import (CHEAP_SECONDS, _interleaved, _time_to_error, apply_repeats,  # noqa: F401
                            ladder_points_used, retime, retime_plan)


def add_arguments(parser) -> None:
    parser.add_argument("--rooms", default="scroll,hall", help="comma-separated: scroll, hall")
    parser.add_argument("--pack", default=None,
                        help="pack of paintings (default: smooth synthetic paintings, built in a temporary directory)")
    parser.add_argument("--width", type=int, default=96, help="still width (default 96)")
    parser.add_argument("--height", type=int, default=54, help="still height (default 54)")
    parser.add_argument("--supersample", type=int, default=3,
                        help="rays per pixel per axis of the default-settings stills (default 3)")
    parser.add_argument("--photons", default="8,10,12,14,16,18,20",
                        help="photons emitted, as comma-separated powers of two (default 8,10,12,14,16,18,20)")
    parser.add_argument("--disc-photons", default="19",
                        help="photon counts (powers of two) tried with the surface disc only (default 19: between "
                             "the grid's counts near the hall's floor, where only the disc gets; empty: none)")
    parser.add_argument("--coarse-photons", default="6,7",
                        help="photon counts (powers of two) tried with the sphere and spacings of diag/12 and coarser "
                             "only (default 6,7: the cheapest stills, for Mitsuba's 1 spp; empty: none)")
    parser.add_argument("--spacings", default="5,6,8,12,25,50,100,200",
                        help="bake spacings as fractions 1/N of the room's diagonal (default 5,6,8,12,25,50,100,200: "
                             "the coarse ones, cheap to bake, are where the 1-spp end's fastest stills are)")
    parser.add_argument("--bake-samples", default="1,4,16,64",
                        help="emitter samples per lattice point (default 1,4,16,64)")
    parser.add_argument("--gather-strides", default="1,2",
                        help="bake gather strides tried at spacings of diag/100 and finer (default 1,2)")
    parser.add_argument("--disc", action=argparse.BooleanOptionalAction, default=True,
                        help="also try the surface-disc gather at multiples of the auto radius (--disc-radii; "
                             "spacings diag/25 and finer, 1-16 samples; default on)")
    parser.add_argument("--disc-radii", default="2,4",
                        help="the disc's radii as multiples of the auto radius (default 2,4; the larger ones "
                             "with 4 and 16 samples only)")
    parser.add_argument("--disc-details", default="fine,coarse",
                        help="how finely the bake clips the discs: fine (up to 128 rays) and/or coarse "
                             "(up to 32; bake(coarse_disc=True)); default fine,coarse")
    parser.add_argument("--final-gathers", default="0,16",
                        help="bake(final_gather=...) rays per lattice point tried at every configuration "
                             "(default 0,16: none, the cheap end's, and the bake's default)")
    parser.add_argument("--supersamples", default="1,3,5",
                        help="rays per pixel per axis of the configurations' stills (default 1,3,5)")
    parser.add_argument("--default-photons", type=int, default=20,
                        help="log2 photons of the default-settings comparison of baked against full (default 20)")
    parser.add_argument("--full-samples", type=int, default=64,
                        help="emitter samples per pixel of the full-lighting oracle (default 64)")
    parser.add_argument("--reference-spp", type=int, default=4096, help="Mitsuba reference spp (default 4096)")
    parser.add_argument("--reference-cache", default="build/gallery-reference",
                        help="directory where the reference images are kept between runs")
    parser.add_argument("--mitsuba-spp", default="1,4,16,64,256,1024,4096",
                        help="Mitsuba spp ladder for its time to each error (default 1,4,16,64,256,1024,4096: "
                             "4096 so that the scroll's floor, below 1024 spp's error, is measured, not bounded)")
    parser.add_argument("--timing-repeats", type=int, default=3,
                        help="re-timings, interleaved, of each target's chosen configuration and of the Mitsuba "
                             "ladder points it is compared with; speedups are ratios of medians (default 3)")
    parser.add_argument("--cheap-repeats", type=int, default=30,
                        help="re-timings of the chosen configurations and ladder points whose single timing "
                             f"is at most {CHEAP_SECONDS * 1e3:.0f} ms (millisecond jobs are the noisiest; "
                             "default 30)")
    parser.add_argument("--grid", action=argparse.BooleanOptionalAction, default=True,
                        help="the grid of configurations and its Pareto front (default on; --no-grid: "
                             "the knob's curve and the default settings only)")
    parser.add_argument("--knob", action=argparse.BooleanOptionalAction, default=True,
                        help="the curve along the quality knob (gallery/quality.py: its steps, the levels "
                             "among them, and the bake's defaults), re-timed as the front's targets (default on)")
    parser.add_argument("--quick", action="store_true", help="small settings, for a smoke test")
    parser.add_argument("--out", default="bench/gallery", help="directory for results.json and plots")


def smooth_painting(width: int, height: int, seed: int) -> np.ndarray:
    """Low-frequency colour fields (a few sinusoids per channel): every mip level and filter
    agree to first order, so the comparison measures light, not texture filtering."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:height, 0:width].astype(np.float64)
    x, y = x / width, y / height
    img = np.zeros((height, width, 3))
    for c in range(3):
        field = np.full_like(x, rng.uniform(0.3, 0.6))
        for _ in range(3):
            fx, fy, ph = rng.uniform(0.5, 3), rng.uniform(0.5, 3), rng.uniform(0, 2 * math.pi)
            field += rng.uniform(0.05, 0.2) * np.sin(2 * math.pi * (fx * x + fy * y) + ph)
        img[..., c] = field
    return (np.clip(img, 0.02, 0.98) * 255).astype(np.uint8)


def build_bench_pack(directory: Path):
    from .. import build_pack

    path = Path(directory) / "gallery.pack"
    images = [smooth_painting(8192, 342, 0)] + [smooth_painting(2048, 1536, s) for s in range(1, 8)]
    names = ["scroll"] + [f"painting{s}" for s in range(1, 8)]
    return build_pack(images, path, tile_size=128, border=4, names=names, force=True)


def _still(gal, vt, lighting: str, width: int, height: int, ss: int, fov: float):
    cam = gal.camera((width * ss, height * ss), fov=fov)
    t0 = time.perf_counter()
    img = gal.render_display(cam, vt, lighting=lighting)
    seconds = time.perf_counter() - t0
    return img.reshape(height, ss, width, ss, 3).mean(axis=(1, 3)), seconds


def _mitsuba(mi, scene, spp: int, seed: int):
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, spp=spp, seed=seed), np.float32)
    return img, time.perf_counter() - t0


def reference_key(gal, cam, spp: int, seed: int) -> str:
    """A digest of everything the Mitsuba reference depends on: the room's surfaces and
    paintings (their Mitsuba-level texels), the camera, spp and seed, and Mitsuba's version."""
    import hashlib

    import mitsuba as mi

    from ..gallery.gallery import _check_slot, _check_surface
    from ..pack import read_level

    h = hashlib.sha256()
    h.update(repr((mi.__version__, spp, seed, cam.width, cam.height, float(cam.fov), tuple(cam.position),
                   tuple(cam.forward), tuple(cam.up))).encode())
    for s in gal.spec.surfaces:
        v, t, albedo, emission = _check_surface(s)
        h.update(np.ascontiguousarray(v, np.float32).tobytes() + np.ascontiguousarray(t, np.int64).tobytes())
        h.update(repr((tuple(albedo), tuple(emission))).encode())
    for i, slot in enumerate(gal.spec.paintings):
        h.update(repr(_check_slot(slot)).encode())
        h.update(read_level(gal.pack, gal.slot_paintings[i], gal.mitsuba_level(i)).tobytes())
    return h.hexdigest()[:16]


def cached_reference(mi, gal, cam, spp: int, cache: Path, seed: int = 0) -> tuple[np.ndarray, float]:
    """Mitsuba's image of the room at `spp` (the reference), computed once and kept in `cache`
    (keyed by reference_key): a 4096-spp reference takes minutes."""
    cache.mkdir(parents=True, exist_ok=True)
    path = cache / f"reference_{reference_key(gal, cam, spp, seed)}.npz"
    if path.exists():
        with np.load(path) as z:
            return z["image"], float(z["seconds"])
    scene = mi.load_dict(gal.to_mitsuba_dict(cam))
    img, seconds = _mitsuba(mi, scene, spp, seed)
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, image=img, seconds=seconds)
    tmp.replace(path)
    return img, seconds


def _ints(text: str, what: str) -> list[int]:
    try:
        values = [int(x) for x in text.split(",") if x]
    except ValueError:
        raise UserError(f"{what} is a comma-separated list of integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise UserError(f"{what} needs positive integers, got {text!r}")
    return values


def run(args) -> int:
    from .. import TilePack, VirtualTexture
    from ..gallery import Gallery, builtin_room
    from ..gallery.accuracy import image_errors, write_comparison
    from ..gallery.exposure import room_display
    from ..photon import relmse

    rooms = [r for r in args.rooms.split(",") if r]
    for r in rooms:
        if r not in ROOMS:
            raise UserError(f"unknown room {r!r} (benchmarked: {', '.join(ROOMS)})")
    if args.quick:
        args.width, args.height, args.supersample = 32, 18, 2
        args.photons, args.spacings, args.bake_samples, args.default_photons = "14,16", "25,50", "4,16", 16
        args.supersamples, args.disc, args.coarse_photons = "1,2", False, ""
        args.final_gathers = args.final_gathers if args.final_gathers != "0,16" else "16"
        args.full_samples, args.reference_spp, args.mitsuba_spp = 16, 64, "1,4,16"
        args.cheap_repeats = min(args.cheap_repeats, args.timing_repeats)
    if min(args.width, args.height, args.supersample, args.reference_spp, args.full_samples, args.timing_repeats,
           args.cheap_repeats) < 1:
        raise UserError("--width, --height, --supersample, --full-samples, --reference-spp, --timing-repeats "
                        "and --cheap-repeats "
                        "must be >= 1")
    photons = _ints(args.photons, "--photons")
    disc_photons = sorted(set(_ints(args.disc_photons, "--disc-photons")) - set(photons)) if (
        args.disc and args.disc_photons) else []
    coarse_photons = sorted(set(_ints(args.coarse_photons, "--coarse-photons")) - set(photons)) if (
        args.coarse_photons) else []
    spacings = _ints(args.spacings, "--spacings")
    bake_samples = _ints(args.bake_samples, "--bake-samples")
    supersamples = _ints(args.supersamples, "--supersamples")
    try:
        final_gathers = sorted({int(x) for x in args.final_gathers.split(",") if x})
    except ValueError:
        raise UserError(f"--final-gathers are integers, got {args.final_gathers!r}") from None
    if not final_gathers or min(final_gathers) < 0 or max(final_gathers) > 4096:
        raise UserError(f"--final-gathers are rays in [0, 4096], got {args.final_gathers!r}")
    strides = _ints(args.gather_strides, "--gather-strides")
    if not set(strides) <= {1, 2}:
        raise UserError("--gather-strides takes 1 and/or 2")
    disc_radii = _ints(args.disc_radii, "--disc-radii") if args.disc else []
    # (disc radius as a multiple of the auto radius, 0 for the sphere; spacing diag/n; samples;
    # gather stride; the discs clipped coarsely, bake(coarse_disc=True)). The disc's gathers
    # on every (n <= 50) or every other point, or on every other or fourth (n >= 100; a gather
    # at every point of a fine lattice never pays for itself), and only where the gathers'
    # sub-lattice stays within the disc's radius.
    details = [d for d in args.disc_details.split(",") if d]
    if not set(details) <= {"fine", "coarse"} or (args.disc and not details):
        raise UserError(f"--disc-details takes fine and/or coarse, got {args.disc_details!r}")
    # The bake's direct light: Lambert's polygon formula times the shadow rays' visible
    # fraction (bake(analytic_direct=True), the default) everywhere; at 1 sample also the
    # plain sample mean, since the formula costs more than the one shadow ray per point that
    # the cheapest stills spend (2.4x the bake in the hall) and pays only where direct light's
    # noise dominates (the scroll; not the hall, whose error there is the photons').
    grid = [(0, n, ls, stride, False, analytic) for n in spacings for ls in bake_samples
            for stride in (strides if n >= 100 else [1]) for analytic in ((True, False) if ls == 1 else (True,))]
    grid += [(m, n, ls, stride, coarse, True) for m in disc_radii for n in spacings if n >= 25
             for ls in bake_samples if ls <= 16 and (m == min(disc_radii) or ls >= 4)
             for stride in ((1, 2) if n <= 50 else (2, 4)) for coarse in
             sorted({d == "coarse" for d in details})]
    if not args.grid:
        grid = []
    ladder = _ints(args.mitsuba_spp, "--mitsuba-spp")
    if max(photons + disc_photons + coarse_photons + [args.default_photons]) > 30:
        raise UserError("--photons, --disc-photons and --default-photons are powers of two up to 2^30")
    try:
        import mitsuba as mi
    except ImportError:
        raise UserError("the gallery benchmark needs mitsuba (pip install mitsuba)") from None
    mi.set_variant("scalar_rgb")
    from tqdm import tqdm

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    import os
    import tempfile

    scratch = tempfile.TemporaryDirectory(prefix="gigascroll-bench-gallery-")
    pack = TilePack(args.pack) if args.pack else build_bench_pack(scratch.name)
    results = {"settings": {k: getattr(args, k) for k in (
                   "width", "height", "supersample", "supersamples", "gather_strides", "disc", "disc_radii", "disc_details", "photons", "disc_photons", "coarse_photons", "spacings", "bake_samples", "final_gathers", "default_photons",
                   "full_samples", "reference_spp", "mitsuba_spp", "timing_repeats", "cheap_repeats")},
               "load_average": os.getloadavg(), "rooms": {}}
    fov = 60.0
    per_room = (2 + len(ladder) + len(photons) * len(grid) + len(disc_photons) * sum(1 for d, *_ in grid if d)
                + len(coarse_photons) * sum(1 for d, *_ in grid if not d)
                + len(set(spacings) | {200}) + (len(STEPS) + 1 if args.knob else 0))
    steps = tqdm(total=len(rooms) * per_room, desc="gallery bench", unit="step")
    for name in rooms:
        spec = builtin_room(name, pack)
        gal = Gallery.from_room(spec, pack)
        vt = VirtualTexture(pack, (48, 48))
        cam = gal.camera((args.width * args.supersample, args.height * args.supersample), fov=fov)
        tiles = gal.stream(cam, vt)
        r = {"triangles": gal.triangle_count, "paintings": gal.painting_count, "tiles_streamed": tiles}
        mcam = gal.camera((args.width, args.height), fov=fov)
        ref, ref_seconds = cached_reference(mi, gal, mcam, args.reference_spp, Path(args.reference_cache))
        r["reference"] = {"spp": args.reference_spp, "seconds": ref_seconds}
        steps.update()
        # Mitsuba's ladder (another seed than the reference's).
        mscene = mi.load_dict(gal.to_mitsuba_dict(mcam))
        r["mitsuba"] = []
        for spp in ladder:
            img, seconds = _mitsuba(mi, mscene, spp, seed=1)
            r["mitsuba"].append({"spp": spp, "seconds": seconds, **image_errors(img, ref)})
            steps.update()
        diag = math.dist(*gal.bounds)
        # Our configurations, each timed end to end.
        configs, auto_radius = [], {}
        # Wall-clock times of the calls: "map" is everything light() does besides tracing
        # (the painting albedo read, dropping hidden photons, the hash grid).
        runs = [(p, d) for p in sorted(photons + disc_photons + coarse_photons) for d in sorted({d for d, *_ in grid})
                if (d or p not in disc_photons) and not (d and p in coarse_photons)]
        for p, disc in runs:
            if disc and p not in auto_radius:  # a disc-only count: the auto radius from a light() of its own
                auto_radius[p] = gal.light(vt, photons=1 << p)["radius"]
            if disc and disc * auto_radius[p] > 0.1 * diag:
                # Discs wider than twice the auto radius's clamp (few photons): a gather
                # over a tenth of the room clips against most of it, slow and blurred.
                steps.update(sum(1 for d, *_ in grid if d == disc))
                continue
            if disc:  # the disc at a multiple of the auto radius (read from the sphere's run before)
                t0 = time.perf_counter()
                light_radius = disc * auto_radius[p]
                st = gal.light(vt, photons=1 << p, radius=light_radius, disc=True)
            else:
                t0 = time.perf_counter()
                light_radius = None
                st = gal.light(vt, photons=1 << p)
                auto_radius[p] = st["radius"]
            light_seconds = time.perf_counter() - t0
            for d, n, ls, stride, coarse, analytic in grid:
                if d != disc:
                    continue
                if (disc and stride > 1 and stride * diag / n > st["radius"]) or (p in coarse_photons and n > 12):
                    steps.update()
                    continue
                for fg in final_gathers:
                    t0 = time.perf_counter()
                    # The grid's final gather is the dense one (at every point, whatever the stride).
                    bst = gal.bake(spacing=diag / n, light_samples=ls, gather_stride=stride, coarse_disc=coarse,
                                   analytic_direct=analytic, final_gather=fg, sparse_final_gather=False)
                    bake_seconds = time.perf_counter() - t0
                    for ss in supersamples:
                        img, still_seconds = _still(gal, vt, "baked", args.width, args.height, ss, fov)
                        c = {"photons_log2": p, "photons_stored": st["photons_stored"], "radius_m": st["radius"],
                             "disc": bool(disc), "disc_radius_factor": disc, "coarse_disc": coarse, "analytic_direct": analytic,
                             "diagonal_over": n, "spacing_m": bst["spacing"], "bake_samples": ls,
                             "gather_stride": stride, "final_gather": fg, "supersample": ss, "bake_points": bst["bake_points"],
                             "sides_skipped": bst["bake_sides_skipped"], "photon_seconds": st["photon_seconds"],
                             "build_seconds": light_seconds - st["photon_seconds"], "bake_seconds": bake_seconds,
                             "still_seconds": still_seconds, **image_errors(img, ref)}
                        c["total_seconds"] = light_seconds + bake_seconds + still_seconds
                        c["light_radius"] = light_radius  # what light() was given (None: auto)
                        configs.append(c)
                steps.update()
        r["configs"] = configs
        r["front"] = pareto_front(configs)
        single = compare_with_mitsuba(configs, r["mitsuba"])
        # The chosen configurations and the Mitsuba points they are compared with, re-timed.
        rerun_errors = {}

        def time_ours(c):
            t0 = time.perf_counter()
            gal.light(vt, photons=1 << c["photons_log2"], radius=c["light_radius"], disc=c["disc"])
            gal.bake(spacing=diag / c["diagonal_over"], light_samples=c["bake_samples"],
                     gather_stride=c["gather_stride"], coarse_disc=c["coarse_disc"],
                     analytic_direct=c["analytic_direct"], final_gather=c.get("final_gather", 16),
                     sparse_final_gather=False)
            seconds = time.perf_counter() - t0
            img, still_seconds = _still(gal, vt, "baked", args.width, args.height, c["supersample"], fov)
            rerun_errors.setdefault(id(c), []).append(relmse(img, ref))
            steps.update()
            return seconds + still_seconds

        def time_mitsuba(spp):
            steps.update()
            return _mitsuba(mi, mscene, spp, seed=1)[1]

        steps.total += sum(n for *_, n in retime_plan(single, r["mitsuba"], args.timing_repeats,
                                                       args.cheap_repeats)[1])
        ours_times, mitsuba_times = retime(single, r["mitsuba"], time_ours, time_mitsuba, args.timing_repeats,
                                           args.cheap_repeats)
        r["targets"] = apply_repeats(single, r["mitsuba"], ours_times, mitsuba_times)
        for t in r["targets"]:
            if t["ours"] is not None and id(t["ours"]) in rerun_errors:
                t["ours_repeat_relmse"] = rerun_errors[id(t["ours"])]
        for l in r["mitsuba"]:
            if mitsuba_times.get(l["spp"]):
                l["repeat_seconds"] = mitsuba_times[l["spp"]]
                l["median_seconds"] = float(np.median(mitsuba_times[l["spp"]]))
        r["timing_repeats"] = args.timing_repeats
        if args.knob:
            from .gallery_knob import measure_knob, print_knob

            r["knob"] = measure_knob(
                gal, vt, spec, ref, r["mitsuba"],
                lambda g, v, ss: _still(g, v, "baked", args.width, args.height, ss, fov), time_mitsuba, args,
                steps.update)
            print_knob(name, r["knob"])
        del mscene
        # The default settings: baked (16 stratified samples) against full lighting on the
        # same photon map, both against the reference, and the bake-spacing curve.
        st = gal.light(vt, photons=1 << args.default_photons, light_samples=args.full_samples)
        full, full_seconds = _still(gal, vt, "full", args.width, args.height, args.supersample, fov)
        r["default"] = {"photons_log2": args.default_photons, "photon_seconds": st["photon_seconds"],
                        "build_seconds": st["build_seconds"], "full_samples": args.full_samples,
                        "full": {"seconds": full_seconds, **image_errors(full, ref)}, "baked": []}
        steps.update()
        default_still = None
        for n in sorted(set(spacings) | {200}):
            bst = gal.bake(spacing=diag / n)
            baked, baked_seconds = _still(gal, vt, "baked", args.width, args.height, args.supersample, fov)
            default_still = baked if n == 200 else default_still
            r["default"]["baked"].append({
                "diagonal_over": n, "spacing_m": bst["spacing"], "bake_points": bst["bake_points"],
                "bake_seconds": bst["bake_seconds"], "still_seconds": baked_seconds,
                "relmse_vs_full": relmse(baked, full), **image_errors(baked, ref)})
            steps.update()
        results["rooms"][name] = r
        # ours baked (default spacing), ours full, Mitsuba's reference: one camera response
        write_comparison(out / f"{name}_stills.png", [default_still, full, ref], room_display(spec))
        _plot(name, r, out)
        _print(name, r)
    steps.close()
    del pack
    scratch.cleanup()
    write_results(out, results)
    print(f"\nwrote {out / 'results.json'} and {out / 'configs.csv'}")
    return 0


CONFIG_COLUMNS = ("room", "photons_log2", "photons_stored", "radius_m", "disc", "disc_radius_factor", "coarse_disc",
                  "analytic_direct",
                  "diagonal_over", "spacing_m",
                  "bake_samples", "gather_stride", "final_gather", "supersample", "bake_points", "sides_skipped",
                  "photon_seconds", "build_seconds", "bake_seconds", "still_seconds", "total_seconds",
                  "relmse", "psnr", "flip")


def write_results(out: Path, results: dict) -> None:
    """results.json without the grid (front, targets, ladder, defaults), and every
    configuration of the grid as one row of configs.csv."""
    import csv
    import io

    rows = []
    slim = {**results, "rooms": {}}
    for name, r in results["rooms"].items():
        rows += [{"room": name, **c} for c in r["configs"]]
        slim["rooms"][name] = {k: v for k, v in r.items() if k != "configs"}
    text = io.StringIO()
    w = csv.DictWriter(text, CONFIG_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for row in rows:
        w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items()})
    tmp = out / "configs.csv.tmp"
    tmp.write_text(text.getvalue())
    tmp.replace(out / "configs.csv")
    write_json(out / "results.json", slim, indent=1)


def pareto_front(configs: list[dict]) -> list[dict]:
    """The configurations no other one beats in both total time and relMSE, fastest first."""
    front = []
    for c in sorted(configs, key=lambda c: (c["total_seconds"], c["relmse"])):
        if not front or c["relmse"] < front[-1]["relmse"]:
            front.append(c)
    return front


def fastest_reaching(configs: list[dict], error: float) -> dict | None:
    """Our fastest configuration whose relMSE is at most `error`, None when none reaches it."""
    ok = [c for c in configs if c["relmse"] <= error]
    return min(ok, key=lambda c: c["total_seconds"]) if ok else None


def compare_with_mitsuba(configs: list[dict], ladder: list[dict]) -> list[dict]:
    """For each of Mitsuba's ladder errors (its time measured) and the errors of our front
    (its time interpolated along the ladder): our fastest configuration reaching that error and
    the ratio of times. Errors our front does not reach are listed with `ours` None."""
    targets = [(l["relmse"], l["seconds"], l["spp"]) for l in ladder]
    targets += [(c["relmse"], _time_to_error(ladder, c["relmse"]), None) for c in pareto_front(configs)]
    rows = []
    for error, mitsuba_seconds, spp in sorted(targets, key=lambda t: -t[0]):
        best = fastest_reaching(configs, error)
        # Below Mitsuba's ladder its time is more than its largest run's: a lower bound.
        bound = max(l["seconds"] for l in ladder) if mitsuba_seconds is None else None
        rows.append({"relmse": error, "mitsuba_spp": spp, "mitsuba_seconds": mitsuba_seconds,
                     "ours": best, "speedup": (mitsuba_seconds / best["total_seconds"]
                                               if best is not None and mitsuba_seconds else None),
                     "speedup_at_least": (bound / best["total_seconds"] if best is not None and bound else None)})
    return rows


def _config_name(c: dict) -> str:
    s = c.get("gather_stride", 1)
    stride = f", gathers / {s * s}" if s > 1 else ""
    disc = (f", disc r x {c.get('disc_radius_factor', 2)}{' coarse' if c.get('coarse_disc') else ''}"
            if c.get("disc") else "")
    mean = ", sample mean" if not c.get("analytic_direct", True) else ""
    fg = c.get("final_gather", 16)
    stride += f", final gather {fg}" if fg != 16 else ""
    return (f"2^{c['photons_log2']}{disc}, diag/{c['diagonal_over']}, {c['bake_samples']} samples{mean}{stride}, "
            f"{c['supersample']}x{c['supersample']} rays")


def _print(name: str, r: dict) -> None:
    print(f"\n{name}: {r['triangles']} triangles, {r['paintings']} paintings, {r['tiles_streamed']} tiles streamed")
    for l in r["mitsuba"]:
        print(f"  mitsuba {l['spp']:5d} spp {l['seconds']:7.2f} s   relMSE {l['relmse']:.2e}  FLIP {l['flip']:.3f}")
    print("  our front (photon + build + bake + still = total):")
    for c in r["front"]:
        print(f"    {_config_name(c):68s} {c['photon_seconds']:.2f} + {c['build_seconds']:.2f} + "
              f"{c['bake_seconds']:.2f} + {c['still_seconds']:.3f} = {c['total_seconds']:.2f} s   "
              f"relMSE {c['relmse']:.2e}  FLIP {c['flip']:.3f}")
    print("  target relMSE -> Mitsuba s -> ours s -> speedup (single run; medians of the repeats, their range):")
    for t in r["targets"]:
        m = f"{t['mitsuba_seconds']:.2f} s" if t["mitsuba_seconds"] else "not reached"
        o = f"{t['ours']['total_seconds']:.3f} s" if t["ours"] else "not reached"
        sp = (f"{t['speedup']:.1f}x" if t["speedup"] else
              f">{t['speedup_at_least']:.1f}x" if t["speedup_at_least"] else "-")
        med = ""
        if "ours_median_seconds" in t:
            if t["speedup_median"] is not None:
                lo, hi = t["speedup_range"]
                med = (f"   median {t['mitsuba_median_seconds']:.3f} s / {t['ours_median_seconds']:.4f} s = "
                       f"{t['speedup_median']:.1f}x ({lo:.1f}-{hi:.1f}x)")
            else:
                med = f"   median > {t['mitsuba_median_bound_seconds']:.2f} s / {t['ours_median_seconds']:.4f} s"
                med += f" = >{t['speedup_at_least_median']:.1f}x"
        print(f"    {t['relmse']:.2e}  ({t['mitsuba_spp'] or 'interp.'} spp) {m:>12s} {o:>12s} {sp:>7s}{med}")
    d = r["default"]
    print(f"  default settings, 2^{d['photons_log2']} photons: full ({d['full_samples']} samples) relMSE "
          f"{d['full']['relmse']:.2e}")
    for b in d["baked"]:
        print(f"    bake diag/{b['diagonal_over']:<4d} {b['bake_seconds']:.2f} s  relMSE {b['relmse']:.2e} "
              f"(vs full {b['relmse_vs_full']:.1e})")


def _plot(name: str, r: dict, out: Path) -> None:
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 5.0))
    # Mitsuba's ladder at the median of its repeated timings where the bench re-timed it (the
    # times the speedups are computed from), else its single run.
    m = r["mitsuba"]
    mitsuba_s = [x.get("median_seconds") or x["seconds"] for x in m]
    repeated = any(x.get("median_seconds") for x in m)
    a.loglog(mitsuba_s, [x["relmse"] for x in m], "^-", color="C0",
             label="Mitsuba path tracer" + (" (median of repeats)" if repeated else ""))
    a.loglog([t / 10 for t in mitsuba_s], [x["relmse"] for x in m], ":", color="C0", label="Mitsuba time / 10")
    cs = r["configs"]
    a.loglog([c["total_seconds"] for c in cs], [c["relmse"] for c in cs], ".", color="0.6",
             label="baked still, each configuration")
    f = r["front"]
    a.step([c["total_seconds"] for c in f], [c["relmse"] for c in f], "o-", where="post", color="C3",
           label="baked still, Pareto front")
    timed = [t for t in r.get("targets", []) if t.get("ours_median_seconds")]
    if timed:
        a.loglog([t["ours_median_seconds"] for t in timed], [t["relmse"] for t in timed], "D",
                 color="C2", ms=5, label="ours re-timed at each target (median)")
    if r.get("knob"):
        from .gallery_knob import plot_knob

        plot_knob(a, r["knob"])
    a.set_xlabel("seconds (photon pass + map + bake + still)")
    a.set_ylabel("relMSE against the reference")
    # Below the axes: inside, it hid the front's fine end (bottom left of the plot).
    a.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2)
    a.set_title(f"{name}: time to error")
    d = r["default"]["baked"]
    b.loglog([x["spacing_m"] for x in d], [x["relmse_vs_full"] for x in d], "o-", label="baked vs full")
    b.loglog([x["spacing_m"] for x in d], [x["relmse"] for x in d], "s-", label="baked vs reference")
    b.axhline(r["default"]["full"]["relmse"], color="k", ls="--", label="full vs reference")
    b.set_xlabel("bake spacing (m)")
    b.set_ylabel("relMSE")
    b.legend(fontsize=8)
    b.set_title(f"{name}: baking at the default settings")
    fig.tight_layout()
    save_figure(fig, out / f"{name}_front.png", dpi=110)

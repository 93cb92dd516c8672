"""`gigascroll bench gallery`: the built-in `scroll` and `hall` rooms with a pack of smooth
synthetic paintings: photon pass, bake, and a still per lighting mode, with each still's error
against Mitsuba 3's path tracer (relMSE, PSNR, HDR-FLIP) beside its time, the error that baking
adds over full lighting as a curve against bake spacing and bake time, and Mitsuba's own time
to reach the baked still's error on the same cores.

Our stills cast --supersample^2 rays per pixel (pixel centres of a finer grid, box-filtered)
because Mitsuba's box pixel filter averages over the pixel; times are for that many rays.
Times are single runs on a shared machine (noisy); ratios are within the same run.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import pyplot, save_figure, write_json

ROOMS = ("scroll", "hall")


def add_arguments(parser) -> None:
    parser.add_argument("--rooms", default="scroll,hall", help="comma-separated: scroll, hall")
    parser.add_argument("--pack", default=None,
                        help="pack of paintings (default: smooth synthetic paintings, built in a temporary directory)")
    parser.add_argument("--width", type=int, default=96, help="still width (default 96)")
    parser.add_argument("--height", type=int, default=54, help="still height (default 54)")
    parser.add_argument("--supersample", type=int, default=3, help="rays per pixel per axis (default 3)")
    parser.add_argument("--photons", type=int, default=1 << 20, help="photons emitted (default 2^20)")
    parser.add_argument("--spacings", default="400,200,100,50",
                        help="bake spacings as fractions 1/N of the room's diagonal (default 400,200,100,50)")
    parser.add_argument("--reference-spp", type=int, default=1024, help="Mitsuba reference spp (default 1024)")
    parser.add_argument("--mitsuba-spp", default="1,2,4,8,16,32,64,128,256",
                        help="Mitsuba spp ladder for its time to the same error")
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


def run(args) -> int:
    from .. import TilePack, VirtualTexture
    from ..gallery import Gallery, builtin_room
    from ..gallery.accuracy import image_errors
    from ..photon import relmse

    rooms = [r for r in args.rooms.split(",") if r]
    for r in rooms:
        if r not in ROOMS:
            raise UserError(f"unknown room {r!r} (benchmarked: {', '.join(ROOMS)})")
    if args.quick:
        args.width, args.height, args.supersample, args.photons = 32, 18, 2, 1 << 17
        args.spacings, args.reference_spp, args.mitsuba_spp = "100,50", 64, "1,4,16"
    if min(args.width, args.height, args.supersample, args.photons, args.reference_spp) < 1:
        raise UserError("--width, --height, --supersample, --photons and --reference-spp must be >= 1")
    try:
        spacings = [int(s) for s in args.spacings.split(",") if s]
        ladder = [int(s) for s in args.mitsuba_spp.split(",") if s]
    except ValueError:
        raise UserError("--spacings and --mitsuba-spp are comma-separated integers") from None
    try:
        import mitsuba as mi
    except ImportError:
        raise UserError("the gallery benchmark needs mitsuba (pip install mitsuba)") from None
    mi.set_variant("scalar_rgb")
    from tqdm import tqdm

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    import tempfile

    scratch = tempfile.TemporaryDirectory(prefix="gigascroll-bench-gallery-")
    pack = TilePack(args.pack) if args.pack else build_bench_pack(scratch.name)
    results = {"settings": {k: getattr(args, k) for k in ("width", "height", "supersample", "photons",
                                                         "spacings", "reference_spp", "mitsuba_spp")},
               "rooms": {}}
    fov = 60.0
    steps = tqdm(total=len(rooms) * (4 + len(spacings) + len(ladder)), desc="gallery bench", unit="step")
    for name in rooms:
        spec = builtin_room(name, pack)
        gal = Gallery.from_room(spec, pack)
        vt_side = 48
        vt = VirtualTexture(pack, (vt_side, vt_side))
        cam = gal.camera((args.width * args.supersample, args.height * args.supersample), fov=fov)
        tiles = gal.stream(cam, vt)
        r = {"triangles": gal.triangle_count, "paintings": gal.painting_count, "tiles_streamed": tiles}
        gal.light(vt, photons=args.photons)
        st = gal.stats
        r.update(photon_seconds=st["photon_seconds"], grid_seconds=st["build_seconds"],
                 photons_stored=st["photons_stored"], radius_m=st["radius"], albedo_levels=st["albedo_levels"])
        steps.update()
        # The reference, and Mitsuba's ladder (another seed) for its time to each error.
        mscene = mi.load_dict(gal.to_mitsuba_dict(gal.camera((args.width, args.height), fov=fov)))
        ref, ref_seconds = _mitsuba(mi, mscene, args.reference_spp, seed=0)
        r["reference"] = {"spp": args.reference_spp, "seconds": ref_seconds}
        steps.update()
        full, full_seconds = _still(gal, vt, "full", args.width, args.height, args.supersample, fov)
        r["full"] = {"seconds": full_seconds, **image_errors(full, ref)}
        steps.update()
        curve = []
        diag = math.dist(*gal.bounds)
        for n in spacings:
            gal.bake(spacing=diag / n)
            bst = gal.stats
            baked, baked_seconds = _still(gal, vt, "baked", args.width, args.height, args.supersample, fov)
            curve.append({"spacing_m": bst["spacing"], "diagonal_over": n, "bake_points": bst["bake_points"],
                          "bake_seconds": bst["bake_seconds"], "still_seconds": baked_seconds,
                          "relmse_vs_full": relmse(baked, full), **image_errors(baked, ref)})
            steps.update()
        r["baked"] = curve
        ladder_results = []
        for spp in ladder:
            img, seconds = _mitsuba(mi, mscene, spp, seed=1)
            ladder_results.append({"spp": spp, "seconds": seconds, **image_errors(img, ref)})
            steps.update()
        r["mitsuba"] = ladder_results
        # Mitsuba's time to the baked still's error (the finest bake), interpolated in log-log.
        best = min(curve, key=lambda c: c["relmse"])
        r["mitsuba_seconds_to_baked_error"] = _time_to_error(ladder_results, best["relmse"])
        r["speedup_baked_still"] = (r["mitsuba_seconds_to_baked_error"] / best["still_seconds"]
                                    if r["mitsuba_seconds_to_baked_error"] else None)
        r["mitsuba_seconds_to_full_error"] = _time_to_error(ladder_results, r["full"]["relmse"])
        steps.update()
        results["rooms"][name] = r
        _plot(name, r, out)
        _print(name, r)
    steps.close()
    del pack
    scratch.cleanup()
    write_json(out / "results.json", results, indent=1)
    print(f"\nwrote {out / 'results.json'}")
    return 0


def _time_to_error(ladder: list[dict], error: float) -> float | None:
    """Seconds Mitsuba needs for `error` (relMSE), log-log interpolated along its ladder;
    None when even its largest spp does not reach it."""
    pts = sorted((l["relmse"], l["seconds"]) for l in ladder)
    if error < pts[0][0]:
        return None
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 <= error <= e1:
            if e1 == e0:
                return t0
            w = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    return pts[-1][1]  # our error is above the ladder's worst: its cheapest run already beats it


def _print(name: str, r: dict) -> None:
    print(f"\n{name}: {r['triangles']} triangles, {r['paintings']} paintings, {r['tiles_streamed']} tiles streamed")
    print(f"  photon pass {r['photon_seconds']:.2f} s ({r['photons_stored']} stored, radius {r['radius_m']:.3f} m), "
          f"grid {r['grid_seconds']:.2f} s")
    f = r["full"]
    print(f"  full still  {f['seconds']:.2f} s   relMSE {f['relmse']:.2e}  PSNR {f['psnr']:.1f} dB  FLIP {f['flip']:.3f}")
    for c in r["baked"]:
        print(f"  bake 1/{c['diagonal_over']:<4} {c['bake_seconds']:6.2f} s ({c['bake_points']} points)  still "
              f"{c['still_seconds']:.3f} s   relMSE {c['relmse']:.2e} (vs full {c['relmse_vs_full']:.1e})  "
              f"PSNR {c['psnr']:.1f} dB  FLIP {c['flip']:.3f}")
    for l in r["mitsuba"]:
        print(f"  mitsuba {l['spp']:4d} spp {l['seconds']:7.2f} s   relMSE {l['relmse']:.2e}  FLIP {l['flip']:.3f}")
    t = r["mitsuba_seconds_to_baked_error"]
    print(f"  Mitsuba to the baked still's error: {t:.2f} s" if t else
          "  Mitsuba does not reach the baked still's error on its ladder")


def _plot(name: str, r: dict, out: Path) -> None:
    plt = pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    c = r["baked"]
    a.loglog([x["spacing_m"] for x in c], [x["relmse_vs_full"] for x in c], "o-", label="baked vs full")
    a.loglog([x["spacing_m"] for x in c], [x["relmse"] for x in c], "s-", label="baked vs Mitsuba")
    a.axhline(r["full"]["relmse"], color="k", ls="--", label="full vs Mitsuba")
    a.set_xlabel("bake spacing (m)")
    a.set_ylabel("relMSE")
    a.legend()
    a.set_title(f"{name}: error against bake spacing")
    b.loglog([x["bake_seconds"] for x in c], [x["relmse_vs_full"] for x in c], "o-", label="bake: error vs full")
    m = r["mitsuba"]
    b.loglog([x["seconds"] for x in m], [x["relmse"] for x in m], "^-", label="Mitsuba path tracer")
    b.loglog([x["still_seconds"] for x in c], [x["relmse"] for x in c], "s", label="baked still vs Mitsuba")
    b.set_xlabel("seconds")
    b.set_ylabel("relMSE")
    b.legend()
    b.set_title(f"{name}: error against time")
    fig.tight_layout()
    save_figure(fig, out / f"{name}_error.png", dpi=110)

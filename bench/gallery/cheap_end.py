"""The cheap end of `gigascroll bench gallery` (issue 13 §5): our cheapest baked stills end to
end (light + bake + still, as the bench's time_ours) against Mitsuba's 1 and 4 spp, timed in
interleaved rounds (every other round in reverse order) so that load drifts fall on both.

    python bench/gallery/cheap_end.py [--rooms scroll,hall] [--repeats 40]
        [--save images.npz | --compare images.npz]

Per configuration: its relMSE against the bench's cached Mitsuba reference (4096 spp, computed
once, like the bench), the median (min-max) of each stage and of the total, and Mitsuba's
median time at 1 and 4 spp with their errors. --save writes every configuration's image;
--compare checks them bit for bit against such a file (e.g. written by another build).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

# (log2 photons, bake spacing as diagonal / n, bake light samples): the grid's cheapest
# points and cheaper candidates.
CONFIGS = [(6, 6, 1), (6, 12, 1), (8, 12, 1), (10, 12, 1), (8, 12, 4), (10, 12, 4), (8, 6, 1), (10, 6, 1)]
WIDTH, HEIGHT, FOV = 96, 54, 60.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rooms", default="scroll,hall")
    ap.add_argument("--repeats", type=int, default=40)
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--reference-cache", default="build/gallery-reference")
    ap.add_argument("--save", default=None)
    ap.add_argument("--compare", default=None)
    args = ap.parse_args()

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    from gigascroll import VirtualTexture
    from gigascroll.benchmarks.gallery import _mitsuba, _still, build_bench_pack, cached_reference
    from gigascroll.gallery import Gallery, builtin_room
    from gigascroll.photon import relmse

    scratch = tempfile.TemporaryDirectory()
    pack = build_bench_pack(scratch.name)
    images, mismatches = {}, 0
    expected = dict(np.load(args.compare)) if args.compare else None
    fmt = lambda a: f"{np.median(a) * 1e3:6.2f} ({min(a) * 1e3:.2f}-{max(a) * 1e3:.2f})"
    for room in [r for r in args.rooms.split(",") if r]:
        gal = Gallery.from_room(builtin_room(room, pack), pack)
        vt = VirtualTexture(pack, (48, 48))
        gal.stream(gal.camera((WIDTH * 3, HEIGHT * 3), fov=FOV), vt)  # as the bench streams
        mcam = gal.camera((WIDTH, HEIGHT), fov=FOV)
        ref, _ = cached_reference(mi, gal, mcam, args.reference_spp, Path(args.reference_cache))
        mscene = mi.load_dict(gal.to_mitsuba_dict(mcam))
        diag = math.dist(*gal.bounds)

        def ours(c):
            p, n, ls = c
            t0 = time.perf_counter()
            gal.light(vt, photons=1 << p)
            t1 = time.perf_counter()
            gal.bake(spacing=diag / n, light_samples=ls)
            t2 = time.perf_counter()
            img, still = _still(gal, vt, "baked", WIDTH, HEIGHT, 1, FOV)
            return img, (t1 - t0, t2 - t1, still, t2 - t0 + still)

        errors = {}
        for c in CONFIGS:
            img, _ = ours(c)
            errors[c] = relmse(img, ref)
            key = f"{room}_{c[0]}_{c[1]}_{c[2]}"
            images[key] = img
            if expected is not None and key in expected and not np.array_equal(expected[key], img):
                mismatches += 1
                print(f"{key}: image differs (max abs diff {np.abs(expected[key] - img).max():.3g})")
        mits_err = {spp: relmse(_mitsuba(mi, mscene, spp, 1)[0], ref) for spp in (1, 4)}
        times = {c: [] for c in CONFIGS}
        mits = {1: [], 4: []}
        for r in range(3 + args.repeats):  # 3 warm-up rounds
            jobs = [("ours", c) for c in CONFIGS] + [("mitsuba", 1), ("mitsuba", 4)]
            for kind, c in (jobs if r % 2 == 0 else jobs[::-1]):
                if kind == "ours":
                    t = ours(c)[1]
                    if r >= 3:
                        times[c].append(t)
                else:
                    t = _mitsuba(mi, mscene, c, 1)[1]
                    if r >= 3:
                        mits[c].append(t)
        print(f"\n{room}: Mitsuba scalar_rgb 1 spp {fmt(mits[1])} ms, relMSE {mits_err[1]:.3g}; "
              f"4 spp {fmt(mits[4])} ms, relMSE {mits_err[4]:.3g}")
        print("config (photons, spacing, samples) | relMSE | light ms | bake ms | still ms | total ms | "
              "speedup vs 1 spp, 4 spp (medians)")
        for c in CONFIGS:
            t = np.array(times[c])
            total = np.median(t[:, 3])
            print(f"2^{c[0]:<2}, diag/{c[1]:<2}, {c[2]} | {errors[c]:.3g} | {fmt(t[:, 0])} | {fmt(t[:, 1])} | "
                  f"{fmt(t[:, 2])} | {fmt(t[:, 3])} | {np.median(mits[1]) / total:5.1f}x, "
                  f"{np.median(mits[4]) / total:5.1f}x")
    if args.save:
        np.savez(args.save, **images)
    if expected is not None:
        print(f"\n{len(images) - mismatches} of {len(images)} images bit-identical to {args.compare}")
    return 1 if mismatches else 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The cheap end of `gigascroll bench gallery` (issue 13 §5): our cheapest baked stills end to
end (light + bake + still, as the bench's time_ours) against Mitsuba's 1 and 4 spp, timed in
interleaved rounds (every other round in reverse order) so that load drifts fall on both.

    python bench/gallery/cheap_end.py [--rooms scroll,hall] [--repeats 40] [--baseline PYTHON]

Per configuration: its relMSE against the bench's cached Mitsuba reference (4096 spp, computed
once, like the bench), the median (min-max) of each stage and of the total, and Mitsuba's
median time at 1 and 4 spp with their errors. --baseline PYTHON: the same configurations also
run in that interpreter (another build of gigascroll, e.g. the main branch's environment),
call for call alternating with ours, so both see the same load; its images are compared with
ours bit for bit and its times printed beside ours.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# (log2 photons, bake spacing as diagonal / n, bake light samples): the grid's cheapest
# points and cheaper candidates.
CONFIGS = [(6, 6, 1), (6, 12, 1), (8, 6, 1), (8, 12, 1), (10, 6, 1), (10, 12, 1), (8, 12, 4), (10, 12, 4)]
WIDTH, HEIGHT, FOV = 96, 54, 60.0


class Room:
    """A room of the bench with its streamed virtual texture, as the bench sets it up."""

    def __init__(self, name: str, pack):
        from gigascroll import VirtualTexture
        from gigascroll.gallery import Gallery, builtin_room

        self.gal = Gallery.from_room(builtin_room(name, pack), pack)
        self.vt = VirtualTexture(pack, (48, 48))
        self.gal.stream(self.gal.camera((WIDTH * 3, HEIGHT * 3), fov=FOV), self.vt)
        self.diag = math.dist(*self.gal.bounds)

    def run(self, c):
        """(image, (light, bake, still, total) seconds) of configuration c from scratch."""
        from gigascroll.benchmarks.gallery import _still

        p, n, ls = c
        t0 = time.perf_counter()
        self.gal.light(self.vt, photons=1 << p)
        t1 = time.perf_counter()
        self.gal.bake(spacing=self.diag / n, light_samples=ls)
        t2 = time.perf_counter()
        img, still = _still(self.gal, self.vt, "baked", WIDTH, HEIGHT, 1, FOV)
        return img, (t1 - t0, t2 - t1, still, t2 - t0 + still)


def serve(pack_path: str, room: str) -> int:
    """The --baseline side: runs configurations sent on stdin, one per line ("p n ls"), and
    answers each with its times (JSON); "image p n ls PATH" saves that image to PATH."""
    from gigascroll import TilePack

    r = Room(room, TilePack(pack_path))
    print("ready", flush=True)
    for line in sys.stdin:
        words = line.split()
        if words[0] == "image":
            np.save(words[4], r.run(tuple(int(w) for w in words[1:4]))[0])
            print("saved", flush=True)
        else:
            print(json.dumps(r.run(tuple(int(w) for w in words))[1]), flush=True)
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rooms", default="scroll,hall")
    ap.add_argument("--repeats", type=int, default=40)
    ap.add_argument("--reference-spp", type=int, default=4096)
    ap.add_argument("--reference-cache", default="build/gallery-reference")
    ap.add_argument("--baseline", default=None, help="another interpreter whose gigascroll to compare with")
    ap.add_argument("--serve", nargs=2, metavar=("PACK", "ROOM"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.serve:
        return serve(*args.serve)

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    from gigascroll.benchmarks.gallery import _mitsuba, build_bench_pack, cached_reference
    from gigascroll.photon import relmse

    scratch = tempfile.TemporaryDirectory()
    pack = build_bench_pack(scratch.name)
    mismatches = 0
    fmt = lambda a: f"{np.median(a) * 1e3:5.2f} ({min(a) * 1e3:.2f}-{max(a) * 1e3:.2f})"
    for name in [r for r in args.rooms.split(",") if r]:
        room = Room(name, pack)
        mcam = room.gal.camera((WIDTH, HEIGHT), fov=FOV)
        ref, _ = cached_reference(mi, room.gal, mcam, args.reference_spp, Path(args.reference_cache))
        mscene = mi.load_dict(room.gal.to_mitsuba_dict(mcam))
        base = None
        if args.baseline:
            base = subprocess.Popen([args.baseline, __file__, "--serve", str(pack.path), name],
                                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
            assert base.stdout.readline().strip() == "ready"

        def baseline(c):
            base.stdin.write(" ".join(map(str, c)) + "\n")
            base.stdin.flush()
            return json.loads(base.stdout.readline())

        errors = {}
        for c in CONFIGS:
            img, _ = room.run(c)
            errors[c] = relmse(img, ref)
            if base:
                path = Path(scratch.name) / "baseline.npy"
                base.stdin.write(f"image {c[0]} {c[1]} {c[2]} {path}\n")
                base.stdin.flush()
                assert base.stdout.readline().strip() == "saved"
                if not np.array_equal(np.load(path), img):
                    mismatches += 1
                    print(f"{name} {c}: the baseline's image differs")
        mits_err = {spp: relmse(_mitsuba(mi, mscene, spp, 1)[0], ref) for spp in (1, 4)}
        times = {c: [] for c in CONFIGS}
        base_times = {c: [] for c in CONFIGS}
        mits = {1: [], 4: []}
        for r in range(3 + args.repeats):  # 3 warm-up rounds
            jobs = [(kind, c) for c in CONFIGS for kind in (("ours", "baseline") if base else ("ours",))]
            jobs += [("mitsuba", 1), ("mitsuba", 4)]
            for kind, c in (jobs if r % 2 == 0 else jobs[::-1]):
                if kind == "mitsuba":
                    t = _mitsuba(mi, mscene, c, 1)[1]
                else:
                    t = room.run(c)[1] if kind == "ours" else baseline(c)
                if r >= 3:
                    (mits if kind == "mitsuba" else times if kind == "ours" else base_times)[c].append(t)
        if base:
            base.stdin.close()
            base.wait()
        print(f"\n{name}: Mitsuba scalar_rgb 1 spp {fmt(mits[1])} ms, relMSE {mits_err[1]:.3g}; "
              f"4 spp {fmt(mits[4])} ms, relMSE {mits_err[4]:.3g}")
        print("photons, spacing, samples | relMSE | light ms | bake ms | still ms | total ms | "
              "speedup (medians) vs 1 spp, 4 spp" + (" | baseline total ms | baseline / ours" if base else ""))
        for c in CONFIGS:
            t = np.array(times[c])
            total = np.median(t[:, 3])
            line = (f"2^{c[0]:<2}, diag/{c[1]:<2}, {c[2]} | {errors[c]:.3g} | {fmt(t[:, 0])} | {fmt(t[:, 1])} | "
                    f"{fmt(t[:, 2])} | {fmt(t[:, 3])} | {np.median(mits[1]) / total:5.1f}x, "
                    f"{np.median(mits[4]) / total:5.1f}x")
            if base:
                b = np.array(base_times[c])[:, 3]
                line += f" | {fmt(b)} | {np.median(b) / total:.2f}"
            print(line)
    if args.baseline:
        print(f"\nimages bit-identical to the baseline's: {'all' if mismatches == 0 else f'{mismatches} differ'}")
    return 1 if mismatches else 0


if __name__ == "__main__":
    raise SystemExit(main())

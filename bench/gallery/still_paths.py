"""The gallery bench's stills through Gallery.render_display's two paths: the packet display
pass (the default for baked lighting without hits) against the per-pixel path
(reference=True), call for call alternating, on one and on two threads.

    python bench/gallery/still_paths.py [--repeats 200] [--supersamples 1,3]

Per room and still size: the largest difference relative to the image's maximum, and the
median time of each path (ms).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time

import numpy as np

WIDTH, HEIGHT, FOV = 96, 54, 60.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--supersamples", default="1,3")
    args = ap.parse_args()
    from gigascroll import VirtualTexture
    from gigascroll.benchmarks.gallery import build_bench_pack
    from gigascroll.gallery import Gallery, builtin_room

    scratch = tempfile.TemporaryDirectory()
    pack = build_bench_pack(scratch.name)
    print("room, still | max |difference| / max | packet pass T1, T2 ms | per-pixel T1, T2 ms | per-pixel / packet (T2)")
    for name in ("hall", "scroll"):
        gal = Gallery.from_room(builtin_room(name, pack), pack)
        vt = VirtualTexture(pack, (48, 48))
        gal.stream(gal.camera((WIDTH * 3, HEIGHT * 3), fov=FOV), vt)
        diag = math.dist(*gal.bounds)
        gal.light(vt, photons=1 << 8)
        gal.bake(spacing=diag / 6, light_samples=1)
        for ss in (int(s) for s in args.supersamples.split(",")):
            cam = gal.camera((WIDTH * ss, HEIGHT * ss), fov=FOV)
            fast = gal.render_display(cam, vt, lighting="baked")
            ref = gal.render_display(cam, vt, lighting="baked", reference=True)
            diff = float(np.abs(fast - ref).max() / ref.max())
            t = {(ref_path, T): [] for ref_path in (False, True) for T in (1, 2)}
            for _ in range(args.repeats):
                for key in t:
                    t0 = time.perf_counter()
                    gal.render_display(cam, vt, lighting="baked", threads=key[1], reference=key[0])
                    t[key].append(time.perf_counter() - t0)
            m = {k: float(np.median(v)) * 1e3 for k, v in t.items()}
            print(f"{name}, {WIDTH * ss} x {HEIGHT * ss} | {diff:.2e} | {m[False, 1]:.3f}, {m[False, 2]:.3f} | "
                  f"{m[True, 1]:.3f}, {m[True, 2]:.3f} | {m[True, 2] / m[False, 2]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Why the gallery bench's millisecond timings scatter, and what more re-timings give
(bench/RESULTS.md, the gallery section).

    python bench/gallery/timing_noise.py [--rounds 40]

1. The process's CPU time in the first 1-50 ms after `mi.render` returns (Mitsuba's worker
   still running), medians of 20 renders.
2. Cold caches: a 20 000-double numpy sum and `Gallery.camera()` timed back to back, after
   12 ms of sleep and after 12 ms of Python spinning (medians of 60).
3. The bench's cheapest configurations (light + bake + still, as its time_ours) in `--rounds`
   rounds interleaved with Mitsuba's 1 spp (every other round reversed), each round once as
   the bench runs them and once waiting before every timed job until the process is idle:
   medians and Mitsuba's 1 spp over ours.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cheap_end import FOV, HEIGHT, WIDTH, Room  # noqa: E402

# (log2 photons, spacing diag / n, light samples, analytic_direct): the bench's choices at the
# 1-spp end in its runs of 2026-12-02.
CONFIGS = {"hall": [(7, 12, 1, False), (7, 8, 1, True), (7, 5, 1, False), (8, 5, 1, True)],
           "scroll": [(7, 8, 1, False), (7, 5, 1, False)]}


def wait_idle(window: float = 0.002, busy: float = 0.1, timeout: float = 0.2) -> None:
    """Until the process used under `busy` of a core over `window` seconds (or `timeout`)."""
    end = time.perf_counter() + timeout
    while time.perf_counter() < end:
        c0, w0 = time.process_time(), time.perf_counter()
        time.sleep(window)
        if time.process_time() - c0 < busy * (time.perf_counter() - w0):
            return


def spin(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=40)
    args = ap.parse_args()
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    from gigascroll.benchmarks.gallery import _mitsuba, _still, build_bench_pack

    scratch = tempfile.TemporaryDirectory()
    pack = build_bench_pack(scratch.name)
    for name in ("hall", "scroll"):
        room = Room(name, pack)
        gal = room.gal
        scene = mi.load_dict(gal.to_mitsuba_dict(gal.camera((WIDTH, HEIGHT), fov=FOV)))
        if name == "hall":
            for _ in range(3):
                mi.render(scene, spp=1)
            after = {d: [] for d in (0.001, 0.002, 0.005, 0.01, 0.02, 0.05)}
            for _ in range(20):
                mi.render(scene, spp=1)
                c0, w0 = time.process_time(), time.perf_counter()
                trace = []
                while time.perf_counter() - w0 < 0.05:
                    time.sleep(0.0005)
                    trace.append((time.perf_counter() - w0, time.process_time() - c0))
                for d in after:
                    after[d].append(next((c for w, c in trace if w >= d), trace[-1][1]))
            print("process CPU time after mi.render returned (medians of 20): " + ", ".join(
                f"{np.median(v) * 1e3:.1f} ms in {d * 1e3:g} ms" for d, v in after.items()))
            z = np.random.default_rng(0).random(20000)
            for what, call in (("numpy sum of 20000", z.sum),
                               ("Gallery.camera()", lambda: gal.camera((WIDTH, HEIGHT), fov=FOV))):
                t = {"back to back": [], "after 12 ms sleep": [], "after 12 ms spinning": []}
                for _ in range(60):
                    for k, gap in (("back to back", lambda: call()), ("after 12 ms sleep", lambda: time.sleep(0.012)),
                                   ("after 12 ms spinning", lambda: spin(0.012))):
                        gap()
                        t0 = time.perf_counter()
                        call()
                        t[k].append(time.perf_counter() - t0)
                print(f"{what}: " + ", ".join(f"{k} {np.median(v) * 1e6:.0f} us" for k, v in t.items()))

        def ours(c):
            p, n, ls, analytic = c
            t0 = time.perf_counter()
            gal.light(room.vt, photons=1 << p)
            gal.bake(spacing=room.diag / n, light_samples=ls, analytic_direct=analytic)
            seconds = time.perf_counter() - t0
            return seconds + _still(gal, room.vt, "baked", WIDTH, HEIGHT, 1, FOV)[1]

        for idle in (False, True):
            jobs = [("mitsuba", None)] + [("ours", c) for c in CONFIGS[name]]
            times = {c: [] for _, c in jobs}
            for r in range(args.rounds):
                for kind, c in (jobs if r % 2 == 0 else jobs[::-1]):
                    if idle:
                        wait_idle()
                    times[c].append(_mitsuba(mi, scene, 1, 1)[1] if kind == "mitsuba" else ours(c))
            m = float(np.median(times[None]))
            print(f"{name}, {args.rounds} rounds, {'waiting for an idle process' if idle else 'as the bench runs'}: "
                  f"Mitsuba 1 spp {m * 1e3:.2f} ms; " + "; ".join(
                      f"2^{c[0]}, diag/{c[1]}, {'ratio' if c[3] else 'mean'} {np.median(times[c]) * 1e3:.3f} ms "
                      f"({m / np.median(times[c]):.1f}x)" for c in CONFIGS[name]))
    return 0


if __name__ == "__main__":
    sys.exit(main())

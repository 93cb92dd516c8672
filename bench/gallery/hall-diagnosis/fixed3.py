import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
gal, vt, mcam = setup()
for rep in range(3):
    for th in (1, 2):
        ts = []
        for _ in range(20):
            t0 = time.perf_counter(); st = gal.light(vt, photons=1 << 10, threads=th); ts.append(time.perf_counter() - t0 - st["photon_seconds"] - st["build_seconds"])
        print(th, "albedo etc. median ms", np.median(ts) * 1e3)

import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
gal, vt, mcam = setup()
for _ in range(3): st = gal.light(vt, photons=1 << 10)
print(st["albedo_levels"], [gal.pack.paintings[i].level_sizes[l] for i, l in zip(gal.slot_paintings, st["albedo_levels"])])
ts = []
for _ in range(20):
    t0 = time.perf_counter(); st = gal.light(vt, photons=1 << 10); ts.append((time.perf_counter() - t0, st["photon_seconds"], st["build_seconds"]))
ts = np.array(ts); print("wall, photon, build (median ms):", np.median(ts, axis=0) * 1e3)

import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
gal, vt, mcam = setup()
for _ in range(5):
    t0 = time.perf_counter(); st = gal.light(vt, photons=1 << 10); print("wall", time.perf_counter() - t0, st["photon_seconds"], st["build_seconds"], file=sys.stderr)

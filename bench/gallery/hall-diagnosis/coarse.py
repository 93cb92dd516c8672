import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
diag = math.dist(*gal.bounds)
for p, mult, n, ls, stride, ss in ((14, 2, 25, 4, 1, 3), (14, 2, 100, 4, 4, 3), (16, 2, 100, 4, 4, 3), (18, 2, 200, 4, 4, 3), (18, 4, 100, 16, 4, 5), (20, 4, 200, 16, 4, 5)):
    r = gal.light(vt, photons=1 << p)["radius"]
    gal.light(vt, photons=1 << p, radius=mult * r, disc=True)
    ts = []
    for _ in range(2):
        t0 = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=ls, gather_stride=stride); ts.append(time.perf_counter() - t0)
    img, _ = _still(gal, vt, "baked", W, H, ss, FOV)
    print(f"2^{p} x{mult} diag/{n} {ls} s{stride} ss{ss}: bake {min(ts):.3f}s relMSE {relmse(img, R):.3e}", flush=True)

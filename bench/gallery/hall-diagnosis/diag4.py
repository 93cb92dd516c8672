import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
Dm = np.load(D / "Ddirect.npz")["image"].astype(np.float64)
den = R ** 2 + 1e-2
def err(a, b=R): return float(np.mean((np.asarray(a, np.float64) - b) ** 2 / den))
diag = math.dist(*gal.bounds)
def still(ss, lighting): return _still(gal, vt, lighting, W, H, ss, FOV)[0].astype(np.float64)
SS = 3
r20 = 0.1195
for inset in sys.argv[1:]:
    os.environ["GS_EDGE_INSET"] = inset
    gal.light(vt, photons=1, radius=1e-7, light_samples=4)
    out = []
    for n in (100, 200):
        gal.bake(spacing=diag / n, light_samples=4); dbake = still(SS, "baked")
        out.append(f"direct/{n} {err(dbake, Dm):.2e}")
        for label, kw in (("sph20", dict(photons=1 << 20)), ("disc2r20", dict(photons=1 << 20, radius=2 * r20, disc=True)),
                          ("disc4r18", dict(photons=1 << 18, radius=4 * r20, disc=True)), ("disc2r18", dict(photons=1 << 18, radius=2 * r20, disc=True))):
            gal.light(vt, light_samples=4, **kw)
            t = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=4, gather_stride=1); tb = time.perf_counter() - t
            b = still(SS, "baked")
            out.append(f"{label}/{n} ind {err(b - dbake + Dm):.2e} tot {err(b):.2e} ({tb:.2f}s)")
        gal.light(vt, photons=1, radius=1e-7, light_samples=4)
    print("inset", inset, " | ".join(out), flush=True)

import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
Dm = np.load(D / "Ddirect.npz")["image"].astype(np.float64)
Im = R - Dm
den = R ** 2 + 1e-2
def err(a, b=R): return float(np.mean((np.asarray(a, np.float64) - b) ** 2 / den))
diag = math.dist(*gal.bounds)
def still(ss, lighting):
    return _still(gal, vt, lighting, W, H, ss, FOV)[0].astype(np.float64)
SS = 3
gal.light(vt, photons=1, radius=1e-7, light_samples=4)
dfull = still(SS, "full")
gal.bake(spacing=diag / 100, light_samples=4)
dbake = still(SS, "baked")
radius = {}
for p in (16, 18, 20, 22):
    st = gal.light(vt, photons=1 << p, light_samples=4); radius[p] = st["radius"]
print("auto radii", radius, flush=True)
def run(label, **kw):
    t = time.perf_counter(); st = gal.light(vt, light_samples=4, **kw); t = time.perf_counter() - t
    ind = still(SS, "full") - dfull
    gal.bake(spacing=diag / 100, light_samples=4)
    indb = still(SS, "baked") - dbake
    print(f"{label:40s} r={st['radius']:.4f} light {t:.2f}s  indirect err full {err(ind + Dm):.3e}  baked/100 {err(indb + Dm):.3e}  "
          f"mean ratio {ind.mean() / Im.mean():.4f}", flush=True)
    return ind
for p in (18, 20, 22):
    run(f"2^{p} auto radius", photons=1 << p)
for p in (18, 20, 22):
    run(f"2^{p} radius fixed r(2^20)", photons=1 << p, radius=radius[20])
for p in (20, 22):
    run(f"2^{p} radius 2 r(2^20)", photons=1 << p, radius=2 * radius[20])
run(f"2^22 radius r(2^22)/2", photons=1 << 22, radius=radius[22] / 2)
for p in (18, 20):
    run(f"2^{p} disc auto", photons=1 << p, disc=True)
    run(f"2^{p} disc 2r", photons=1 << p, radius=2 * radius[p], disc=True)
ind = run("2^22 disc r(2^22)", photons=1 << 22, disc=True)
np.save(D / "ind_best.npy", ind)

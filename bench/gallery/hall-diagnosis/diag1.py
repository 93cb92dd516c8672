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
print("R mean", R.mean(), "max", R.max(), "direct frac", Dm.mean() / R.mean())
print("noise floor check: err(Dm+Im)=", err(Dm + Im))

def still(ss, lighting="baked"):
    return _still(gal, vt, lighting, W, H, ss, FOV)[0].astype(np.float64)

# --- direct only: one photon, tiny radius (gather finds nothing)
gal.light(vt, photons=1, radius=1e-7)
res = {}
for ss in (1, 3, 5, 8):
    gal.bake(spacing=diag / 100, light_samples=4)
    d = still(ss)
    print(f"direct baked diag/100 4smp ss{ss}: err vs Dm {err(d, Dm):.3e}", flush=True)
for n, ls in ((100, 16), (100, 64), (200, 64), (400, 64), (400, 256)):
    t = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=ls); t = time.perf_counter() - t
    for ss in (3, 8):
        d = still(ss)
        print(f"direct baked diag/{n} {ls}smp ss{ss} (bake {t:.2f}s): err vs Dm {err(d, Dm):.3e}", flush=True)
gal.light(vt, photons=1, radius=1e-7, light_samples=256)
for ss in (3, 8):
    d = still(ss, "full")
    print(f"direct full 256smp ss{ss}: err vs Dm {err(d, Dm):.3e}", flush=True)
np.save(D / "direct_full256_ss8.npy", d)

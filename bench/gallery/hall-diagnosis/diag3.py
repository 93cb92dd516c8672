import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still
import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
Dm = np.load(D / "Ddirect.npz")["image"].astype(np.float64)
Im = R - Dm
den = R ** 2 + 1e-2
def emap(a, b=R): return ((np.asarray(a, np.float64) - b) ** 2 / den).mean(axis=2)
diag = math.dist(*gal.bounds)
print("diag", diag, "bounds", gal.bounds)
def still(ss, lighting):
    return _still(gal, vt, lighting, W, H, ss, FOV)[0].astype(np.float64)
SS = 3
# region classes from hits at 8x8
cam8 = gal.camera((W * 8, H * 8), fov=FOV)
gal.light(vt, photons=1, radius=1e-7, light_samples=4)
_, hits = gal.render_display(cam8, vt, lighting="unlit", hits=True)
pos, slot = hits["position"], hits["slot"]
y = pos[..., 1]
cls = np.full(slot.shape, 0)  # 0 escape
cls[np.isfinite(y)] = 1                      # walls / others
cls[np.abs(y) < 1e-3] = 2                    # floor
cls[(np.abs(y - 0.70) < 1e-3) & (slot < 0)] = 3  # table top
cls[slot >= 0] = 4                           # painting
cls[(y > 0.01) & (y < 0.659) & (slot < 0) & (np.abs(pos[..., 2]) < 8) & (pos[..., 0] > -1) & (pos[..., 0] < 3)] = 5  # legs/table sides
names = ["none", "wall/ceiling/other", "floor", "table top", "painting", "table side/legs"]
blk = cls.reshape(H, 8, W, 8).transpose(0, 2, 1, 3).reshape(H, W, 64)
pure = np.all(blk == blk[..., :1], axis=2)
region = np.where(pure, blk[..., 0], 6)
names.append("mixed (edge) pixels")
dfull = still(SS, "full"); gal.bake(spacing=diag / 100, light_samples=4); dbake = still(SS, "baked")
rows = {}
def report(label, img_err):
    tot = img_err.mean()
    parts = {names[k]: img_err[region == k].sum() / img_err.size for k in range(7) if (region == k).any()}
    print(f"{label:34s} total {tot:.2e} | " + ", ".join(f"{k} {v:.1e} ({(region == names.index(k)).mean()*100:.0f}% px)" for k, v in parts.items()), flush=True)
    rows[label] = img_err
report("direct full 4smp vs Dm", emap(dfull, Dm))
report("direct baked/100 4smp vs Dm", emap(dbake, Dm))
for label, kw in (("2^20 sphere auto", dict(photons=1 << 20)), ("2^20 disc 2r", dict(photons=1 << 20, radius=0.239, disc=True)),
                  ("2^22 sphere auto", dict(photons=1 << 22))):
    gal.light(vt, light_samples=4, **kw)
    ind = still(SS, "full") - dfull
    report(label + " ind full", emap(ind + Dm))
    gal.bake(spacing=diag / 100, light_samples=4)
    t = still(SS, "baked")
    report(label + " ind baked", emap(t - dbake + Dm))
    report(label + " total baked", emap(t))
    np.save(D / f"ind_{label.replace(' ', '_').replace('^','')}.npy", ind)
fig, ax = plt.subplots(3, 3, figsize=(15, 6.5))
ax = ax.ravel()
ax[0].imshow(np.clip(R / R.max(), 0, 1) ** (1 / 2.2)); ax[0].set_title("reference")
ax[1].imshow(region, cmap="tab10", vmin=0, vmax=9); ax[1].set_title("regions")
for a, (k, v) in zip(ax[2:], rows.items()):
    im = a.imshow(v, vmin=0, vmax=3e-4); a.set_title(k, fontsize=8)
fig.tight_layout(); fig.savefig(D / "maps.png", dpi=80)

import json, os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still, pareto_front
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
diag = math.dist(*gal.bounds)
configs = []
for p in (16, 18, 20):
    r = gal.light(vt, photons=1 << p)["radius"]
    for mult in (2, 3, 4):
        t0 = time.perf_counter(); gal.light(vt, photons=1 << p, radius=mult * r, disc=True); tl = time.perf_counter() - t0
        for n in (50, 100, 200):
            for ls in (4, 16):
                for stride in ((2,) if mult == 2 else (2, 4)):
                    if mult == 4 and n == 200 and stride == 2: continue
                    t0 = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=ls, gather_stride=stride); tb = time.perf_counter() - t0
                    for ss in (3, 5):
                        img, ts = _still(gal, vt, "baked", W, H, ss, FOV)
                        configs.append(dict(p=p, disc=True, mult=mult, n=n, ls=ls, stride=stride, ss=ss, light=tl, bake=tb, still=ts,
                                            total_seconds=tl + tb + ts, relmse=relmse(img, R)))
        print(p, mult, "done", flush=True)
json.dump(configs, open(D / "sweep2.json", "w"))
for c in sorted(configs, key=lambda c: c["relmse"])[:40]:
    print(f"2^{c['p']} disc x{c['mult']} diag/{c['n']} {c['ls']}smp stride{c['stride']} ss{c['ss']}: "
          f"{c['light']:.3f}+{c['bake']:.3f}+{c['still']:.3f}={c['total_seconds']:.3f}s relMSE {c['relmse']:.2e}")

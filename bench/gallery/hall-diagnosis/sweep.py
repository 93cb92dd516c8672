import json, os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still, pareto_front
gal, vt, mcam = setup()
R = np.load(D / "R.npz")["image"].astype(np.float64)
diag = math.dist(*gal.bounds)
configs = []
inset = sys.argv[1] == "1"
for p in (12, 14, 16, 18, 20):
    for disc, mult in ((False, 1), (True, 2), (True, 4)):
        if disc and p == 20: continue
        st0 = gal.light(vt, photons=1 << p); r = st0["radius"]
        t0 = time.perf_counter()
        st = gal.light(vt, photons=1 << p, radius=mult * r, disc=disc) if disc else gal.light(vt, photons=1 << p)
        tl = time.perf_counter() - t0
        for n in (25, 50, 100, 200):
            for ls in (1, 4, 16):
                for stride in ((1, 2) if n >= 50 else (1,)):
                    t0 = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=ls, gather_stride=stride, inset_edges=inset); tb = time.perf_counter() - t0
                    for ss in (1, 3):
                        img, ts = _still(gal, vt, "baked", W, H, ss, FOV)
                        c = dict(p=p, disc=disc, mult=mult, n=n, ls=ls, stride=stride, ss=ss, light=tl, bake=tb, still=ts,
                                 total_seconds=tl + tb + ts, relmse=relmse(img, R))
                        configs.append(c)
        print(p, disc, mult, "done", flush=True)
json.dump(configs, open(D / f"sweep_{sys.argv[1]}.json", "w"))
for c in pareto_front(configs):
    print(f"2^{c['p']} {'disc x%d' % c['mult'] if c['disc'] else 'sphere'} diag/{c['n']} {c['ls']}smp stride{c['stride']} ss{c['ss']}: "
          f"{c['light']:.3f}+{c['bake']:.3f}+{c['still']:.3f}={c['total_seconds']:.3f}s relMSE {c['relmse']:.2e}")

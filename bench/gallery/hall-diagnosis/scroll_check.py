import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
from gigascroll.benchmarks.gallery import _still
pk = pack()
gal = Gallery.from_room(builtin_room("scroll", pk), pk)
vt = VirtualTexture(pk, (48, 48))
gal.stream(gal.camera((W * 3, H * 3), fov=FOV), vt)
R = np.load(D / "Rscroll.npz")["image"]
diag = math.dist(*gal.bounds)
for p, n, ls, stride, ss in ((10, 12, 1, 1, 1), (10, 25, 16, 1, 1), (16, 50, 64, 1, 3), (18, 200, 64, 2, 1), (20, 200, 64, 2, 1)):
    gal.light(vt, photons=1 << p)
    out = []
    for inset in (False, True):
        t = time.perf_counter(); gal.bake(spacing=diag / n, light_samples=ls, gather_stride=stride, inset_edges=inset); t = time.perf_counter() - t
        img, _ = _still(gal, vt, "baked", W, H, ss, FOV)
        out.append(f"inset={inset}: {relmse(img, R):.3e} ({t:.2f}s)")
    print(f"2^{p} diag/{n} {ls}smp stride{stride} ss{ss}:", " | ".join(out), flush=True)

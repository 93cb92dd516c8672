"""Set-up shared by the hall-floor diagnosis scripts of bench/RESULTS.md ("The hall's floor:
what it was, and the edge inset"): the gallery bench's pack, the hall at its 96 x 54 view and
the cached 4096-spp Mitsuba references. Run each script from the repository root with the
project's Python (`.venv/bin/python bench/gallery/hall-diagnosis/diag1.py`); they write under
build/hall-diagnosis/. They were run on the code before the edge inset: pass
`inset_edges=False` to `bake` to reproduce the "before" figures on today's code."""
import math, time, sys
from pathlib import Path
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_rgb")
from gigascroll import TilePack, VirtualTexture
from gigascroll.gallery import Gallery, builtin_room
from gigascroll.benchmarks.gallery import build_bench_pack, cached_reference, _still
from gigascroll.photon import relmse

D = Path("build/hall-diagnosis")
W, H, FOV = 96, 54, 60.0

def pack():
    p = D / "pack" / "gallery.pack"
    if p.exists():
        return TilePack(p)
    (D / "pack").mkdir(parents=True, exist_ok=True)
    return build_bench_pack(D / "pack")

def setup(pk=None, spec_fn=None):
    pk = pk or pack()
    spec = builtin_room("hall", pk)
    if spec_fn: spec = spec_fn(spec)
    gal = Gallery.from_room(spec, pk)
    vt = VirtualTexture(pk, (48, 48))
    cam = gal.camera((W * 3, H * 3), fov=FOV)
    gal.stream(cam, vt)
    mcam = gal.camera((W, H), fov=FOV)
    return gal, vt, mcam

def mitsuba_ref(gal, mcam, spp, name, max_depth=-1, seed=0, level=None):
    path = D / f"{name}.npz"
    if path.exists():
        with np.load(path) as z: return z["image"]
    sc = mi.load_dict(gal.to_mitsuba_dict(mcam, max_depth=max_depth, levels=level))
    t0 = time.perf_counter()
    img = np.array(mi.render(sc, spp=spp, seed=seed), np.float32)
    print(name, "mitsuba", time.perf_counter() - t0, "s", flush=True)
    np.savez(path, image=img)
    return img

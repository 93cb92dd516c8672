import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
gal, vt, mcam = setup()
ref, s = cached_reference(mi, gal, mcam, 4096, Path("build/gallery-reference"))
np.savez(D / "R.npz", image=ref)
print("R", s, flush=True)
mitsuba_ref(gal, mcam, 4096, "Ddirect", max_depth=2)

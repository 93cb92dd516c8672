import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
pk = pack()
spec = builtin_room("scroll", pk)
gal = Gallery.from_room(spec, pk)
mcam = gal.camera((W, H), fov=FOV)
ref, s = cached_reference(mi, gal, mcam, 4096, Path("build/gallery-reference"))
np.savez(D / "Rscroll.npz", image=ref)
print("scroll ref", s, flush=True)

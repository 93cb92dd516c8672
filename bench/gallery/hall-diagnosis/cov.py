import os, sys; sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common import *
gal, vt, mcam = setup()
cam8 = gal.camera((W * 8, H * 8), fov=FOV)
_, hits = gal.render_display(cam8, vt, lighting="unlit", hits=True)
slot = hits["slot"]
cov = (slot >= 0).reshape(H, 8, W, 8).mean(axis=(1, 3))
print("painting coverage: pixels touched", (cov > 0).sum(), "of", cov.size, "sum coverage (pixel-equivalents)", cov.sum())

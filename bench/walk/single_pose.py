"""One pose of the walk benchmark's scene (mid-walk, its tiles made resident), its display
looped: the stereo display with reuse, the left eye alone, or the bare cast of both eyes; prints
wall and process-CPU milliseconds per frame. For profiling without the set-up, e.g.

    .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo   # or left, bare
    perf stat -e page-faults .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo
"""
import sys, time, argparse, numpy as np
from gigascroll.benchmarks import walk as W
from gigascroll import runtime, views as v
from gigascroll._core import DisplayPass
from gigascroll.gallery.walk import parent_keys
from gigascroll.views.exhibition import Headset
w, h = map(int, sys.argv[1].split("x")); n = int(sys.argv[2]); mode = sys.argv[3]
args = argparse.Namespace(pack=None, photons=1 << 17, threads=0)
pack, room, src, path = W.lit_scroll_walk(args)
vt = runtime.VirtualTexture(pack, (64, 64))
levels = np.array([t.levels for t in src.tiles], np.int64)
frame = len(path) // 2
views = v.frame_cameras(path, frame, headset=Headset(width=w, height=h), magnifier=None)
needed = np.concatenate([src.feedback(cam, fw, fh, 0).ravel() for cam, fw, fh in views[:2]])
needed = np.unique(needed[needed != v.NO_REQUEST]); needed = np.concatenate([needed, parent_keys(needed, levels)])
missing = vt.request(needed)
for key in zip(*(a.tolist() for a in v.unpack_requests(missing))): vt.insert(key, pack.read_tile(*key))
left, right = views[0][0], views[1][0]
d = DisplayPass(); outs = (np.empty((h, w, 3), np.float32), np.empty((h, w, 3), np.float32))
src.display_stereo(d, vt, left, right, True, 0, *outs)
t = time.perf_counter(); c = time.process_time()
for _ in range(n):
    if mode == "stereo": src.display_stereo(d, vt, left, right, True, 0, *outs)
    elif mode == "left": src.display(d, vt, left, 0, out=outs[0])
    else: src.primary_rays(left, 0); src.primary_rays(right, 0)
print(mode, (time.perf_counter() - t) / n * 1e3, "ms wall", (time.process_time() - c) / n * 1e3, "ms cpu")

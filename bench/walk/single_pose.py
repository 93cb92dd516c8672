"""One pose of the walk benchmark's scene (mid-walk by default, its tiles made resident), its
display looped: the stereo display with reuse, the left eye alone, or the bare cast of both eyes;
prints wall and process-CPU milliseconds per frame. For profiling without the set-up, e.g.

    .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo   # or left, bare
    .venv/bin/python bench/walk/single_pose.py 450x480 300 left --frame 120   # another pose
    perf stat -e page-faults .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo

`pose()` is the set-up alone (bench/walk/alternate.py uses it).
"""
import argparse
import os
import sys
import time

import numpy as np


def pose(w, h, frame=None):
    """The lit scroll walk at one frame (default mid-walk) with its tiles resident: a dict of
    the source, the VT, the path, both eyes' cameras, a DisplayPass and two output images."""
    from gigascroll import runtime, views as v
    from gigascroll._core import DisplayPass
    from gigascroll.benchmarks import walk as W
    from gigascroll.gallery.walk import parent_keys
    from gigascroll.views.exhibition import Headset
    args = argparse.Namespace(pack=None, photons=1 << 17, threads=0)
    pack, room, src, path = W.lit_scroll_walk(args)
    vt = runtime.VirtualTexture(pack, (64, 64))
    levels = np.array([t.levels for t in src.tiles], np.int64)

    def cameras(f):
        views = v.frame_cameras(path, f, headset=Headset(width=w, height=h), magnifier=None)
        return views, views[0][0], views[1][0]

    views, left, right = cameras(len(path) // 2 if frame is None else frame)
    needed = np.concatenate([src.feedback(cam, fw, fh, 0).ravel() for cam, fw, fh in views[:2]])
    needed = np.unique(needed[needed != v.NO_REQUEST])
    needed = np.concatenate([needed, parent_keys(needed, levels)])
    missing = vt.request(needed)
    for key in zip(*(a.tolist() for a in v.unpack_requests(missing))):
        vt.insert(key, pack.read_tile(*key))
    outs = (np.empty((h, w, 3), np.float32), np.empty((h, w, 3), np.float32))
    return {"src": src, "vt": vt, "path": path, "left": left, "right": right,
            "cameras": lambda f: cameras(f)[1:], "display": DisplayPass(), "outs": outs}


def main():
    ap = argparse.ArgumentParser(description="one pose of the walk, its display looped")
    ap.add_argument("size", help="per-eye WxH")
    ap.add_argument("n", type=int, help="displays (or bare casts) to loop")
    ap.add_argument("mode", choices=["stereo", "left", "bare"])
    ap.add_argument("--frame", type=int, help="the walk's frame (default: mid-walk)")
    ap.add_argument("--core", help="a core module file to load instead of the installed one")
    a = ap.parse_args()
    if a.core and not os.path.isfile(a.core):
        ap.error(f"--core {a.core}: no such file")
    if a.core:  # before anything imports gigascroll (and with it the installed core)
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from alternate import load_core
        load_core(a.core)
    try:
        w, h = map(int, a.size.split("x"))
        p = pose(w, h, a.frame)
    except ValueError as e:  # a size that is not WxH, a frame off the walk
        ap.error(str(e))
    n, mode = a.n, a.mode
    src, vt, left, right, d, outs = p["src"], p["vt"], p["left"], p["right"], p["display"], p["outs"]
    src.display_stereo(d, vt, left, right, True, 0, *outs)
    t = time.perf_counter()
    c = time.process_time()
    for _ in range(n):
        if mode == "stereo":
            src.display_stereo(d, vt, left, right, True, 0, *outs)
        elif mode == "left":
            src.display(d, vt, left, 0, out=outs[0])
        else:
            src.primary_rays(left, 0)
            src.primary_rays(right, 0)
    print(mode, (time.perf_counter() - t) / n * 1e3, "ms wall", (time.process_time() - c) / n * 1e3, "ms cpu")


if __name__ == "__main__":
    main()

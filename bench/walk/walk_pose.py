"""What the display scripts beside the walk benchmark share (alternate.py, single_pose.py,
frame_hashes.py, loop_frames.py): loading another build of the core module in place of the
installed one, and one pose of the benchmark's scene with its tiles resident. A module of its
own so that the scripts import it and not each other."""
import argparse
import importlib.util
import sys

import numpy as np


def load_core(path):
    """Loads the extension module at `path` as gigascroll._core. Call it before anything
    imports gigascroll, which would otherwise bind the installed core."""
    spec = importlib.util.spec_from_file_location("gigascroll._core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["gigascroll._core"] = module
    spec.loader.exec_module(module)


def pose(w, h, frame=None):
    """The lit scroll walk at one frame (default mid-walk) with its tiles resident: a dict of
    the source, the VT, the path, both eyes' cameras, a DisplayPass and two output images."""
    from gigascroll import runtime, views as v
    from gigascroll._core import DisplayPass
    from gigascroll.benchmarks import walk as W
    from gigascroll.walk.gallery_walk import parent_keys
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

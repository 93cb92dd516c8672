"""One pose of the walk benchmark's scene (mid-walk by default, its tiles made resident), its
display looped: the stereo display with reuse, the left eye alone, or the bare cast of both eyes;
prints wall and process-CPU milliseconds per frame. For profiling without the set-up, e.g.

    .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo   # or left, bare
    .venv/bin/python bench/walk/single_pose.py 450x480 300 left --frame 120   # another pose
    perf stat -e page-faults .venv/bin/python bench/walk/single_pose.py 450x480 300 stereo

The set-up is walk_pose.pose(), which alternate.py and frame_hashes.py share.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from walk_pose import load_core, pose  # noqa: E402  (beside this script)


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

"""The walk's whole loop (GalleryWalk, with the magnifier, oracle off, as `gigascroll bench
walk --parts loop` runs it) at one per-eye size over the walk's first N frames: the mean of
each stage's milliseconds per frame after the first, e.g.

    .venv/bin/python bench/walk/loop_frames.py 56x60 200 --core OLD_core.so
    .venv/bin/python bench/walk/loop_frames.py 56x60 200 --core NEW_core.so
"""
import argparse
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("eye", help="per-eye WxH")
    ap.add_argument("frames", type=int)
    ap.add_argument("--no-magnifier", action="store_true")
    ap.add_argument("--core", help="a core module file to load instead of the installed one")
    a = ap.parse_args()
    if a.core:
        sys.path.insert(0, HERE)
        from walk_pose import load_core
        load_core(a.core)
    from gigascroll import views as v
    from gigascroll.benchmarks import walk as W
    from gigascroll.walk.gallery_walk import GalleryWalk
    pack, room, src, path = W.lit_scroll_walk(argparse.Namespace(pack=None, photons=1 << 17, threads=0))
    n = max(2, min(a.frames, len(path.position)))
    short = v.CameraPath(path.position[:n], path.forward[:n], path.up[:n], path.magnifier_target[:n],
                         path.magnifier_normal[:n], path.fps)
    w, h = map(int, a.eye.split("x"))
    walk = GalleryWalk(src, pack, short, eye=(w, h), oracle=False, threads=0, magnifier=not a.no_magnifier)
    walk.run()
    rec = walk.records[1:]  # the first frame pays for warming up
    keys = ("feedback_ms", "display_ms", "magnifier_display_ms", "total_ms")
    print(" ".join(f"{k} {statistics.mean(r[k] for r in rec):.2f}" for k in keys))


if __name__ == "__main__":
    main()

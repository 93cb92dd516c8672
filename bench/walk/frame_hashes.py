"""Hashes of what the stereo display writes over the walk (both eyes' images, the reuse
sources, both eyes' levels and hit points, the right eye's counts), one per kind, so that two
builds of the core module can be checked bit for bit (the "frames hash equal" of
bench/RESULTS.md's display sections), e.g.

    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --core OLD_core.so
    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --core NEW_core.so
"""
import argparse
import hashlib
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("eye", help="per-eye WxH")
    ap.add_argument("--core", help="a core module file to load instead of the installed one")
    a = ap.parse_args()
    sys.path.insert(0, HERE)
    if a.core:
        from alternate import load_core
        load_core(a.core)
    import numpy as np
    from single_pose import pose
    w, h = map(int, a.eye.split("x"))
    p = pose(w, h)
    src, vt, d, outs, path = p["src"], p["vt"], p["display"], p["outs"], p["path"]
    digests = {k: hashlib.sha256() for k in ("images", "sources", "levels", "hits", "counts")}
    for f in range(0, len(path), max(1, len(path) // 7)):  # seven poses along the walk
        left, right = p["cameras"](f)
        for _ in range(2):  # the second frame reuses the first frame's cleared claims
            src.display_stereo(d, vt, left, right, True, 0, *outs)
        digests["images"].update(outs[0].tobytes())
        digests["images"].update(outs[1].tobytes())
        digests["sources"].update(np.asarray(d.reuse_sources()).tobytes())
        for eye in (0, 1):
            digests["levels"].update(np.asarray(d.lods(eye)).tobytes())
            digests["hits"].update(np.asarray(d.hit_points(eye)).tobytes())
        st = d.right_stats
        digests["counts"].update(repr((st["reused"], st["traced"], st["hits"], st["painting_pixels"])).encode())
    print(" ".join(f"{k}={v.hexdigest()[:16]}" for k, v in digests.items()))


if __name__ == "__main__":
    main()

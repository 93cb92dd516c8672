"""Hashes of what the stereo display writes over the walk (both eyes' images, the reuse
sources, both eyes' levels and hit points, the right eye's counts), one per kind, so that two
builds of the core module can be checked bit for bit (the "frames hash equal" of
bench/RESULTS.md's walk section), e.g.

    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --core OLD_core.so
    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --core NEW_core.so

`--save FILE.npz` also keeps what was hashed, for bench/walk/frame_diff.py to compare two builds
whose frames differ in their last bits (1800 x 1920 an eye over the eight poses: 1.7 GB).
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
    ap.add_argument("--save", metavar="FILE.npz", help="also save the hashed arrays, pose by pose")
    a = ap.parse_args()
    if a.save and not os.access(os.path.dirname(os.path.abspath(a.save)), os.W_OK):
        print(f"frame_hashes.py: cannot write {a.save}", file=sys.stderr)
        sys.exit(2)
    sys.path.insert(0, HERE)
    if a.core:  # before anything imports gigascroll (and with it the installed core)
        from walk_pose import load_core
        load_core(a.core)
    from gigascroll.commands.gallery import parse_eye
    from gigascroll.errors import UserError
    try:
        w, h = parse_eye(a.eye, "the eye")
    except UserError as e:
        print(f"frame_hashes.py: {e}", file=sys.stderr)
        sys.exit(2)
    import numpy as np
    from walk_pose import pose
    p = pose(w, h)
    src, vt, d, outs, path = p["src"], p["vt"], p["display"], p["outs"], p["path"]
    digests = {k: hashlib.sha256() for k in ("images", "sources", "levels", "hits", "counts")}
    saved = {k: [] for k in ("left", "right", "sources", "levels", "hits")}
    for f in range(0, len(path), max(1, len(path) // 7)):  # poses a seventh of the walk apart (eight)
        left, right = p["cameras"](f)
        for _ in range(2):  # the second frame reuses the first frame's cleared claims
            src.display_stereo(d, vt, left, right, True, 0, *outs)
        sources = np.array(d.reuse_sources())
        levels = [np.array(d.lods(eye)) for eye in (0, 1)]
        hits = [np.array(d.hit_points(eye)) for eye in (0, 1)]
        digests["images"].update(outs[0].tobytes())
        digests["images"].update(outs[1].tobytes())
        digests["sources"].update(sources.tobytes())
        for eye in (0, 1):
            digests["levels"].update(levels[eye].tobytes())
            digests["hits"].update(hits[eye].tobytes())
        if a.save:
            saved["left"].append(outs[0].copy())
            saved["right"].append(outs[1].copy())
            saved["sources"].append(sources)
            saved["levels"].append(np.stack(levels))
            saved["hits"].append(np.stack(hits))
        st = d.right_stats
        digests["counts"].update(repr((st["reused"], st["traced"], st["hits"], st["painting_pixels"])).encode())
    print(" ".join(f"{k}={v.hexdigest()[:16]}" for k, v in digests.items()))
    if a.save:
        part = a.save + ".part"  # renamed when whole, so a cut-off save is not taken for one
        with open(part, "wb") as f:
            np.savez(f, **{k: np.stack(v) for k, v in saved.items()})
        os.replace(part, a.save)


if __name__ == "__main__":
    main()

"""How far apart two builds' frames are: two files of `frame_hashes.py --save` (the same eye size,
the same poses), compared pose by pose. For the images, the largest difference relative to the
pixel's value over the channels brighter than 1e-3 (darker ones are absolute) and the share of
pixels that differ at all; for the reuse sources, the levels and the hit points, whether they are
equal. For example

    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --core OLD_core.so --save old.npz
    .venv/bin/python bench/walk/frame_hashes.py 1800x1920 --save new.npz
    .venv/bin/python bench/walk/frame_diff.py old.npz new.npz
"""
import argparse
import sys

import numpy as np


def image_difference(a, b, floor=1e-3):
    """(largest relative difference, share of pixels not bit-equal) of two float images."""
    scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), floor)
    rel = float(np.max(np.abs(a.astype(np.float64) - b) / scale)) if a.size else 0.0
    differ = float(np.mean(np.any(a != b, axis=-1))) if a.size else 0.0
    return rel, differ


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    a = ap.parse_args()
    try:
        old, new = np.load(a.old), np.load(a.new)
        kinds = ("left", "right", "sources", "levels", "hits")
        for k in kinds:
            if k not in old or k not in new or old[k].shape != new[k].shape:
                raise ValueError(f"{k!r} missing or of another shape: not two saves of one walk")
    except (OSError, ValueError) as e:
        print(f"frame_diff: {e}", file=sys.stderr)
        sys.exit(2)
    equal = True
    for pose in range(old["left"].shape[0]):
        cells = []
        for eye in ("left", "right"):
            rel, differ = image_difference(old[eye][pose], new[eye][pose])
            cells.append(f"{eye} {rel:.2g} rel ({differ:.0%} of pixels differ)")
        for k in ("sources", "levels", "hits"):
            same = np.array_equal(old[k][pose], new[k][pose], equal_nan=True)
            equal &= same
            cells.append(f"{k} {'equal' if same else 'DIFFER'}")
        print(f"pose {pose}: " + ", ".join(cells))
    sys.exit(0 if equal else 1)


if __name__ == "__main__":
    main()

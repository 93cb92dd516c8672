"""Two builds of the core module against each other on one pose of the walk, in alternated
processes (how the display's steps in bench/RESULTS.md's walk section were weighed), e.g.

    .venv/bin/python bench/walk/alternate.py OLD_core.so NEW_core.so --eye 1800x1920 --mode left
    .venv/bin/python bench/walk/alternate.py OLD_core.so NEW_core.so --mode right

Each round runs one process per module, old first; each process loads its module in place of
the installed gigascroll._core. Modes:
  left    the left eye's display against the bare cast of its pixels: the median over
          --alternations (12) alternations of 3 displays and 3 bare casts of their
          process-CPU-time ratio, and the ratio of the fastest of each;
  stereo  the same for both eyes with reuse against the bare cast of both eyes;
  right   the right eye with reuse against the left eye (900 x 960 unless --eye) over five
          poses of the walk (4 stereo frames each): the medians of both eyes' stage times, and
          their ratio.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from walk_pose import load_core, pose  # noqa: E402  (beside this script)


def display_ratio(mode, w, h, frame, alternations=12):
    p = pose(w, h, frame)
    src, vt, left, right, d, outs = p["src"], p["vt"], p["left"], p["right"], p["display"], p["outs"]
    ratios, shown, bare = [], [], []
    for _ in range(alternations):
        c = time.process_time()
        for _ in range(3):
            if mode == "stereo":
                src.display_stereo(d, vt, left, right, True, 0, *outs)
            else:
                src.display(d, vt, left, 0, out=outs[0])
        a = (time.process_time() - c) / 3
        c = time.process_time()
        for _ in range(3):
            src.primary_rays(left, 0)
            if mode == "stereo":
                src.primary_rays(right, 0)
        b = (time.process_time() - c) / 3
        ratios.append(a / b), shown.append(a), bare.append(b)
    # The ratio of the fastest display to the fastest bare cast: the other jobs of a shared
    # host only ever add time, so the minima move less from process to process than medians.
    print(f"{mode} ratio median {statistics.median(ratios):.3f} display "
          f"{statistics.median(shown) * 1e3:.1f} ms cpu bare {statistics.median(bare) * 1e3:.1f} ms cpu "
          f"ratio of minima {min(shown) / min(bare):.3f}")


def right_vs_left(w, h):
    p = pose(w, h)
    src, vt, d, outs, path = p["src"], p["vt"], p["display"], p["outs"], p["path"]
    stages = {}
    for frame in range(len(path) // 6, len(path), len(path) // 6):
        left, right = p["cameras"](frame)
        for _ in range(4):
            src.display_stereo(d, vt, left, right, True, 0, *outs)
            for eye, st in (("left", d.left_stats), ("right", d.right_stats)):
                for k in ("rays_seconds", "reuse_seconds", "vt_seconds", "shade_seconds", "total_seconds"):
                    stages.setdefault(f"{eye} {k[:-8]}", []).append(st[k] * 1e3)
    print(" ".join(f"{k} {statistics.median(v):.3f} ms" for k, v in stages.items()))
    print(f"right / left {statistics.median(stages['right total']) / statistics.median(stages['left total']):.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--eye", help="per-eye WxH (default 1800x1920; --mode right 900x960)")
    ap.add_argument("--mode", choices=["left", "stereo", "right"], default="left")
    ap.add_argument("--frame", type=int, help="the walk's frame for left and stereo (default: mid-walk)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--alternations", type=int, default=12, help="left and stereo: per process")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.eye is None:
        a.eye = "900x960" if a.mode == "right" else "1800x1920"
    if a.child:  # before anything imports gigascroll (and with it the installed core)
        load_core(a.child)
    from gigascroll.commands.gallery import parse_eye
    from gigascroll.errors import UserError
    try:
        w, h = parse_eye(a.eye)
        if a.rounds < 1 or a.alternations < 1:
            raise UserError(f"--rounds and --alternations must be >= 1 (got {a.rounds}, {a.alternations})")
    except UserError as e:
        print(f"alternate.py: {e}", file=sys.stderr)
        sys.exit(2)
    if a.child:
        if a.mode == "right":
            right_vs_left(w, h)
        else:
            display_ratio(a.mode, w, h, a.frame, a.alternations)
        return
    for path in (a.old, a.new):
        if not os.path.isfile(path):
            print(f"alternate.py: no module file {path}", file=sys.stderr)
            sys.exit(2)
    for _ in range(a.rounds):
        for name, path in (("old", a.old), ("new", a.new)):
            frame = [] if a.frame is None else ["--frame", str(a.frame)]
            out = subprocess.run([sys.executable, __file__, a.old, a.new, "--eye", a.eye, "--mode",
                                  a.mode, *frame, "--alternations", str(a.alternations), "--child", path],
                                 capture_output=True, text=True)
            if out.returncode:
                print(f"alternate.py: the {name} module's process failed:\n{out.stderr}", file=sys.stderr)
                sys.exit(2)
            lines = out.stdout.strip().splitlines()
            print(name, " | ".join(lines[-1:] if a.mode != "right" else lines[-2:]))


if __name__ == "__main__":
    main()

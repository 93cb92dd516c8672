"""`gigascroll bench pack`: tile-pack build speed and peak memory against libvips dzsave.

Both builders run as child processes on the same tiled BigTIFF of the built-in painting,
with the same geometry (128-texel tiles = 120 payload + 4 border each side, levels down to
one tile, uncompressed RGB tiles), one after the other in this command; time is the child's
own wall time around the build call, peak RSS comes from wait4() for that child alone.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from ..errors import UserError
from ..experiments import pyplot, save_figure, write_json

OURS = """
import sys, time, gigascroll
t = time.perf_counter()
gigascroll.build_pack(sys.argv[1], sys.argv[2], tile_size=128, border=4, codec=sys.argv[3],
                      force=True, threads=int(sys.argv[4]))
print(time.perf_counter() - t)
"""

VIPS = """
import sys, time, pyvips
t = time.perf_counter()
image = pyvips.Image.new_from_file(sys.argv[1], access="sequential")
# tile_size is the payload in libvips; overlap is added on each side: 120 + 2 * 4 = 128.
image.dzsave(sys.argv[2], tile_size=120, overlap=4, depth="onetile", suffix=".raw")
print(time.perf_counter() - t)
"""


def add_arguments(p) -> None:
    p.add_argument("--width", type=int, default=152089, help="painting width (default 152089)")
    p.add_argument("--height", type=int, default=6083, help="painting height (default 6083)")
    p.add_argument("--workdir", default="build/bench-pack",
                   help="cache for the synthesized painting and the outputs (default build/bench-pack)")
    p.add_argument("--repeat", type=int, default=1, help="runs of each builder (median reported)")
    p.add_argument("--codec", default="raw", choices=["raw", "zstd"], help="our codec (default raw)")
    p.add_argument("--threads", type=int, default=0, help="our worker threads (default all cores)")
    p.add_argument("--no-vips", action="store_true", help="skip the libvips run")
    p.add_argument("--keep", action="store_true", help="keep the outputs")
    p.add_argument("--plot", default=None, help="PNG of the comparison (default WORKDIR/bench_pack.png)")


def _dir_bytes(path: Path) -> int:
    if path.is_file():
        return path.stat().st_size
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file())


def _measure(code: str, args: list[str]) -> dict:
    """Runs one builder as a child; its own timing and its peak RSS (wait4 of that child)."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    out, err = proc.stdout.read(), proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise OSError(f"benchmark child failed ({proc.returncode}): {err.strip()[-500:]}")
    return {"seconds": float(out.strip().splitlines()[-1]), "process_seconds": wall,
            "peak_rss_mb": usage.ru_maxrss / 1024.0, "cpu_seconds": usage.ru_utime + usage.ru_stime}


def run(args) -> int:
    from ..pack import synth_painting
    if args.width <= 0 or args.height <= 0 or args.repeat <= 0:
        raise UserError("--width, --height and --repeat must be positive")
    if not args.no_vips:
        try:
            import pyvips  # noqa: F401
        except ImportError as e:
            raise UserError(f"pyvips is needed for the libvips baseline ({e}); or pass --no-vips")
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    src = work / f"ink-{args.width}x{args.height}.tif"
    if not src.exists():
        print(f"synthesizing {src} (cached for later runs)")
        synth_painting(src, args.width, args.height, progress=True)
    mpx = args.width * args.height / 1e6

    runs: dict[str, list[dict]] = {"gigascroll": [], "libvips dzsave": []}
    for r in range(args.repeat):
        out = work / "out.pack"
        print(f"[{r + 1}/{args.repeat}] gigascroll build_pack ({args.codec}) ...", flush=True)
        m = _measure(OURS, [str(src), str(out), args.codec, str(args.threads)])
        m["output_mb"] = _dir_bytes(out) / 2**20
        runs["gigascroll"].append(m)
        if not args.keep:
            shutil.rmtree(out, ignore_errors=True)
        if not args.no_vips:
            base = work / "out-vips"
            shutil.rmtree(base.with_name("out-vips_files"), ignore_errors=True)
            print(f"[{r + 1}/{args.repeat}] libvips dzsave (.raw tiles) ...", flush=True)
            m = _measure(VIPS, [str(src), str(base)])
            m["output_mb"] = (_dir_bytes(base.with_name("out-vips_files")) +
                              _dir_bytes(base.with_suffix(".dzi"))) / 2**20
            runs["libvips dzsave"].append(m)
            if not args.keep:
                shutil.rmtree(base.with_name("out-vips_files"), ignore_errors=True)
                base.with_suffix(".dzi").unlink(missing_ok=True)

    summary = {}
    for name, ms in runs.items():
        if not ms:
            continue
        sec = statistics.median(m["seconds"] for m in ms)
        summary[name] = {"seconds": sec, "mpixel_per_s": mpx / sec,
                         "peak_rss_mb": max(m["peak_rss_mb"] for m in ms),
                         "cpu_seconds": statistics.median(m["cpu_seconds"] for m in ms),
                         "output_mb": ms[-1]["output_mb"], "runs": ms}
    print(f"\npainting {args.width} x {args.height} ({mpx:.0f} Mpixel), tile 128 (120 + 2 x 4), "
          f"{os.cpu_count()} cores")
    print(f"{'builder':<18}{'time s':>9}{'Mpixel/s':>10}{'peak RSS MB':>13}{'CPU s':>8}{'output MB':>11}")
    for name, s in summary.items():
        print(f"{name:<18}{s['seconds']:>9.1f}{s['mpixel_per_s']:>10.1f}{s['peak_rss_mb']:>13.0f}"
              f"{s['cpu_seconds']:>8.1f}{s['output_mb']:>11.0f}")
    result = {"width": args.width, "height": args.height, "codec": args.codec,
              "repeat": args.repeat, "builders": summary}
    if len(summary) == 2:
        ours, vips = summary["gigascroll"], summary["libvips dzsave"]
        result["speed_ratio"] = ours["mpixel_per_s"] / vips["mpixel_per_s"]
        print(f"speed ratio gigascroll / libvips = {result['speed_ratio']:.2f}; "
              f"peak RSS {ours['peak_rss_mb']:.0f} MB vs {vips['peak_rss_mb']:.0f} MB "
              f"(goal: ratio >= 1, RSS < 1024 MB)")
    write_json(work / "bench_pack.json", result, indent=2)
    _plot(summary, Path(args.plot) if args.plot else work / "bench_pack.png", args)
    return 0


def _plot(summary: dict, png: Path, args) -> None:
    names = list(summary)
    fig, axes = pyplot().subplots(1, 2, figsize=(9, 3.2), constrained_layout=True)
    colors = ["tab:blue", "tab:gray"][:len(names)]
    axes[0].bar(names, [summary[n]["mpixel_per_s"] for n in names], color=colors)
    axes[0].set_ylabel("Mpixel/s (higher is better)")
    axes[1].bar(names, [summary[n]["peak_rss_mb"] for n in names], color=colors)
    axes[1].axhline(1024, color="red", ls="--", lw=1, label="1 GB goal")
    axes[1].set_ylabel("peak RSS, MB")
    axes[1].legend()
    fig.suptitle(f"tile-pack build, {args.width} x {args.height}, 128-px tiles")
    save_figure(fig, png, dpi=100)
    print(f"plot: {png}")

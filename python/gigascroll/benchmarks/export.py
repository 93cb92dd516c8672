"""`gigascroll bench export`: `gigascroll export` to each format against libvips from the same
source in the same run: IIIF level-0 tiles and Deep Zoom against `dzsave` (layout iiif3 /
dz, JPEG), the pyramidal BigTIFF against `tiffsave(pyramid=True)` (JPEG).

Ours exports from the pack built from the source (the pack is built once and cached, its
build is not timed here: `gigascroll bench pack` measures that); libvips reads the source
TIFF itself. Each exporter runs as a child process; time is the child's own wall time
around the export call, peak RSS comes from wait4() for that child alone.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

from ..errors import UserError
from ..experiments import write_json
from .pack import _dir_bytes, _measure

OURS = """
import sys, time
from gigascroll.export import export_pack
t = time.perf_counter()
export_pack(sys.argv[1], sys.argv[2], sys.argv[3], quality=int(sys.argv[4]), force=True,
            threads=int(sys.argv[5]))
print(time.perf_counter() - t)
"""

VIPS = """
import sys, time, pyvips
fmt, q, out = sys.argv[2], int(sys.argv[3]), sys.argv[4]
t = time.perf_counter()
image = pyvips.Image.new_from_file(sys.argv[1], access="sequential")
if fmt == "tiff":
    image.tiffsave(out, tile=True, tile_width=256, tile_height=256, pyramid=True,
                   compression="jpeg", Q=q, bigtiff=True)
else:  # tile_size is the payload in libvips: 120, with the pack's border as overlap
    image.dzsave(out, tile_size=120, overlap=4 if fmt == "dzi" else 0, Q=q,
                 layout="iiif3" if fmt == "iiif" else "dz", suffix=f".jpg[Q={q}]")
print(time.perf_counter() - t)
"""


def add_arguments(p) -> None:
    p.add_argument("--width", type=int, default=152089, help="painting width (default 152089)")
    p.add_argument("--height", type=int, default=6083, help="painting height (default 6083)")
    p.add_argument("--workdir", default="build/bench-pack",
                   help="cache for the painting, its pack and the outputs (default build/bench-pack)")
    p.add_argument("--formats", default="iiif,dzi,tiff", help="comma-separated (default all)")
    p.add_argument("--quality", type=int, default=90, help="JPEG quality (default 90)")
    p.add_argument("--repeat", type=int, default=1, help="runs of each exporter (median reported)")
    p.add_argument("--threads", type=int, default=0, help="our worker threads (default all cores)")
    p.add_argument("--no-vips", action="store_true", help="skip the libvips runs")


def _remove(path: Path) -> None:
    for p in (path, path.with_name(path.name + ".dzi"), path.with_name(path.name + "_files")):
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        elif p.exists():
            p.unlink()


def _outputs_mb(path: Path) -> float:
    paths = [path, path.with_name(path.name + ".dzi"), path.with_name(path.name + "_files")]
    return sum(_dir_bytes(p) for p in paths if p.exists()) / 2**20


PREPARE = """
import sys
from gigascroll.pack import build_pack, synth_painting
src, pack, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
if src != "-":
    synth_painting(src, w, h, progress=True)
if pack != "-":
    build_pack(src, pack, tile_size=128, border=4, force=True, progress=True)
"""


def _prepare(src: Path, pack: Path, width: int, height: int) -> None:
    """Synthesizes the painting and builds its pack in a child process: a child forked from a
    large parent would report the parent's peak RSS as its own (ru_maxrss survives exec)."""
    need_src, need_pack = not src.exists(), not (pack / "manifest.json").exists()
    if not (need_src or need_pack):
        return
    print(f"preparing {src if need_src else ''} {pack if need_pack else ''} (cached for later runs)")
    subprocess.run([sys.executable, "-c", PREPARE, str(src) if need_src else "-",
                    str(pack) if need_pack else "-", str(width), str(height)], check=True)


def run(args) -> int:
    formats = [f for f in args.formats.split(",") if f]
    if not formats or any(f not in ("iiif", "dzi", "tiff") for f in formats):
        raise UserError(f"--formats must name iiif, dzi or tiff, got '{args.formats}'")
    if args.width <= 0 or args.height <= 0 or args.repeat <= 0:
        raise UserError("--width, --height and --repeat must be positive")
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    src = work / f"ink-{args.width}x{args.height}.tif"
    pack = work / f"ink-{args.width}x{args.height}.pack"
    _prepare(src, pack, args.width, args.height)
    mpx = args.width * args.height / 1e6

    rows = []
    for fmt in formats:
        for who in ("gigascroll", "libvips") if not args.no_vips else ("gigascroll",):
            ms = []
            for r in range(args.repeat):
                out = work / (f"export-{who}-{fmt}" + (".tif" if fmt == "tiff" else ""))
                _remove(out)
                print(f"[{r + 1}/{args.repeat}] {who} {fmt} ...", flush=True)
                if who == "gigascroll":
                    m = _measure(OURS, [str(pack), str(out), fmt, str(args.quality), str(args.threads)])
                else:
                    m = _measure(VIPS, [str(src), fmt, str(args.quality), str(out)])
                m["output_mb"] = _outputs_mb(out)
                _remove(out)
                ms.append(m)
            sec = statistics.median(m["seconds"] for m in ms)
            rows.append({"format": fmt, "exporter": who, "seconds": sec, "mpixel_per_s": mpx / sec,
                         "peak_rss_mb": max(m["peak_rss_mb"] for m in ms),
                         "cpu_seconds": statistics.median(m["cpu_seconds"] for m in ms),
                         "output_mb": ms[-1]["output_mb"], "runs": ms})
    print(f"\npainting {args.width} x {args.height} ({mpx:.0f} Mpixel), JPEG Q{args.quality}, "
          f"{os.cpu_count()} cores")
    print(f"{'format':<7}{'exporter':<12}{'time s':>9}{'Mpixel/s':>10}{'peak RSS MB':>13}"
          f"{'CPU s':>8}{'output MB':>11}")
    for r in rows:
        print(f"{r['format']:<7}{r['exporter']:<12}{r['seconds']:>9.1f}{r['mpixel_per_s']:>10.1f}"
              f"{r['peak_rss_mb']:>13.0f}{r['cpu_seconds']:>8.1f}{r['output_mb']:>11.0f}")
    write_json(work / "bench_export.json", {"width": args.width, "height": args.height,
                                            "quality": args.quality, "results": rows}, indent=2)
    return 0

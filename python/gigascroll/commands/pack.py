"""`gigascroll pack`: build a tile pack from one or more images."""

from __future__ import annotations

import time


def register(sub) -> None:
    p = sub.add_parser("pack", help="build a tile pack from images",
                       description="Builds a tile pack (one painting per input image) with its "
                       "mip chain, bordered tiles and merged page-table layout.")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="image files (any format "
                   "OpenImageIO reads)")
    p.add_argument("-o", "--output", required=True, help="output pack directory")
    p.add_argument("--tile-size", type=int, default=128, help="tile size in texels (default 128)")
    p.add_argument("--border", type=int, default=4, help="border in texels (default 4)")
    p.add_argument("--codec", default="raw", help="raw (RGB24), zstd (lossless) or bc1 (DXT1 "
                   "blocks, 4 bits per texel, kept compressed in the cache; default raw)")
    p.add_argument("--bc1-fit", default="range", choices=["range", "cluster"],
                   help="bc1 encoder fit: range (fast, default) or cluster (~1.4 dB better PSNR, "
                   "~25x slower)")
    p.add_argument("--layout", default="brkga", choices=["brkga", "shelf"],
                   help="merged page-table packer (default brkga)")
    p.add_argument("--seed", type=int, default=0, help="BRKGA random seed (default 0)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (default: all cores)")
    p.add_argument("--colour", default="convert", choices=["convert", "keep"],
                   help="convert: an embedded ICC profile (or EXR chromaticities) is converted "
                   "to sRGB with LittleCMS; keep: values stored untouched (default convert)")
    p.add_argument("--intent", default="relative",
                   help="rendering intent of the conversion: perceptual, relative (colorimetric, "
                   "the default), saturation or absolute")
    p.add_argument("--no-bpc", dest="bpc", action="store_false",
                   help="no black-point compensation (on by default)")
    p.add_argument("--force", action="store_true", help="overwrite an existing pack")
    p.add_argument("--workers", type=int, default=0,
                   help="build each painting as a shard on a Dask LocalCluster of this many "
                   "worker processes (needs the 'cluster' extra; default 0: one process)")
    p.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                   help="build the shards on this Dask scheduler's workers (they must see the "
                   "output directory)")
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help="bound on each wait for Dask: connecting to the scheduler (default 30 s), "
                   "its first worker and any stretch without workers (default 60 s)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the verified shards a failed sharded build left in OUTPUT.shards/")
    p.add_argument("--instance", action="append", default=[], metavar="NAME=SOURCE",
                   help="add painting NAME sharing input SOURCE's tiles (its index from 0, or "
                   "its painting name): a copy with its own name and page-table place that "
                   "stores nothing; repeatable, the instances follow the inputs")
    p.set_defaults(func=run)


def parse_instances(items) -> list[tuple[str, int | str]]:
    """NAME=SOURCE items as (name, source), SOURCE an index when it is all digits."""
    out = []
    for item in items:
        name, eq, source = item.rpartition("=")
        if not eq or not name or not source:
            raise ValueError(f"--instance {item!r}: expected NAME=SOURCE (SOURCE an input's "
                             "index or painting name)")
        out.append((name, int(source) if source.isascii() and source.isdigit() else source))
    return out


def run(args) -> int:
    from ..pack import build_pack, pack_summary
    if args.threads < 0:
        raise ValueError("--threads must be >= 0")
    if args.workers < 0:
        raise ValueError("--workers must be >= 0")
    t0 = time.perf_counter()
    pack = build_pack(args.inputs, args.output, args.tile_size, args.border, args.codec,
                      force=args.force, layout=args.layout, seed=args.seed,
                      threads=args.threads, bc1_fit=args.bc1_fit, progress=True, colour=args.colour,
                      intent=args.intent, black_point_compensation=args.bpc,
                      workers=args.workers, scheduler=args.scheduler, resume=args.resume,
                      timeout=args.timeout, instances=parse_instances(args.instance) or None)
    seconds = time.perf_counter() - t0
    mpx = sum(p.width * p.height for p in pack.paintings if p.instance_of is None) / 1e6
    print(pack_summary(pack))
    print(f"built in {seconds:.1f} s ({mpx / seconds:.1f} Mpixel/s)")
    return 0

"""`gigascroll export`: a painting of a tile pack as IIIF level-0 tiles, Deep Zoom or a
pyramidal BigTIFF, streamed from the pack's tiles."""

from __future__ import annotations

import time

DEFAULT_PORT = 8000  # export.DEFAULT_IIIF_PORT (not imported here: --help stays light)


def register(sub) -> None:
    p = sub.add_parser("export", help="export a painting to IIIF, Deep Zoom or pyramidal TIFF",
                       description="Writes one painting of a tile pack as IIIF Image API 3.0 "
                       "level-0 static tiles (iiif), Deep Zoom (dzi) or a tiled pyramidal "
                       "BigTIFF (tiff), from the pack's tiles; written atomically.")
    p.add_argument("pack", metavar="PACK", help="tile pack directory")
    p.add_argument("-o", "--output", required=True,
                   help="output: a directory (iiif), OUT.dzi + OUT_files (dzi) or a file (tiff)")
    p.add_argument("--format", required=True, choices=["iiif", "dzi", "tiff"])
    p.add_argument("--painting", default=None, help="painting name or index (default: the first)")
    p.add_argument("--quality", type=int, default=90, help="JPEG quality 1..100 (default 90)")
    p.add_argument("--compression", default="jpeg", choices=["jpeg", "deflate"],
                   help="tiff only: JPEG or lossless deflate (default jpeg)")
    p.add_argument("--base-url", "--iiif-id", dest="base_url", default=None, metavar="URL",
                   help="iiif only: the image service's id in info.json, the absolute http(s) "
                   "URI the directory is served at (the Image API requires an absolute id; "
                   "tile URLs are URL/REGION/SIZE/0/default.jpg). Default "
                   f"http://localhost:{DEFAULT_PORT}/NAME, NAME the output directory's name: "
                   f"where `python -m http.server {DEFAULT_PORT}` run in the output's parent "
                   "directory serves it")
    p.add_argument("--reader", default="core", choices=["core", "python"],
                   help="read the pack with the core or the pure-Python reader (default core)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (default: all cores)")
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..export import default_base_url, export_pack
    if args.threads < 0:
        raise ValueError("--threads must be >= 0")
    base_url = args.base_url
    if args.format == "iiif":
        from ..iiif_presentation import check_http_uri
        base_url = check_http_uri(base_url or default_base_url(args.output), "--base-url")
    elif base_url is not None:
        raise ValueError("--base-url applies to --format iiif only")
    t0 = time.perf_counter()
    path = export_pack(args.pack, args.output, args.format, painting=args.painting,
                       quality=args.quality, compression=args.compression, force=args.force,
                       reader=args.reader, threads=args.threads, progress=True,
                       service_id=base_url)
    print(f"exported {path} in {time.perf_counter() - t0:.1f} s")
    return 0

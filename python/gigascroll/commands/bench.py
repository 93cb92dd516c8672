"""`gigascroll bench WHAT`: scenario benchmarks. Each lives in gigascroll.benchmarks.<what>
with `add_arguments(parser)` and `run(args) -> int`."""

from __future__ import annotations

# what -> one-line description, in the order `gigascroll bench --help` lists them
BENCHMARKS = {
    "pack": "tile-pack build throughput and memory against libvips dzsave",
    "export": "export to IIIF, Deep Zoom and pyramidal TIFF against libvips",
    "queues": "lock-free queues against peer queues and a mutex queue",
    "loader": "seed 000 Table 1: lock-free vs locked tile loading, and VT sampling cost",
    "views": "tile determination: the four request-processing methods against scale",
    "photon": "seed 001 Tables 1-5 and run time against error",
    "bc1": "the bc1 (DXT1) codec: PSNR and FLIP per painting, sampling cost, hit rate per byte",
}


def register(sub) -> None:
    from ..benchmarks import bc1, export, loader, pack, photon, queues, views

    modules = {"pack": pack, "export": export, "queues": queues, "loader": loader, "views": views,
               "photon": photon, "bc1": bc1}
    parser = sub.add_parser("bench", help="run a scenario benchmark")
    whats = parser.add_subparsers(dest="what", metavar="WHAT")
    whats.required = True
    for what, description in BENCHMARKS.items():
        module = modules[what]
        p = whats.add_parser(what, help=description, description=description)
        module.add_arguments(p)
        p.set_defaults(func=module.run)

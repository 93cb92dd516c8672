"""`gigascroll bench WHAT`: scenario benchmarks. Each lives in gigascroll.benchmarks.<what>
with `add_arguments(parser)` and `run(args) -> int`."""

from __future__ import annotations

# what -> one-line description, in the order `gigascroll bench --help` lists them
BENCHMARKS = {
    "pack": "tile-pack build throughput and memory against libvips dzsave",
    "cluster": "sharded pack builds on Dask (1, 2 workers) against a process pool",
    "export": "export to IIIF, Deep Zoom and pyramidal TIFF against libvips",
    "queues": "lock-free queues against peer queues and a mutex queue",
    "loader": "VT-mobile-VR Table 1: lock-free vs locked tile loading, and VT sampling cost",
    "views": "tile determination: the four request-processing methods against scale",
    "photon": "VR-photon-mapping Tables 1-5 and run time against error",
    "gallery": "gallery rooms: photon pass, bake, stills, error against Mitsuba 3",
    "mottle": "the baked light's mottle against Mitsuba 3 on walls, floor and paintings",
    "walk": "the gallery walk: display vs bare rays, stereo reuse, fps per eye size, latency",
    "foveation": "the gallery walk foveated: rays and time saved, requests, error per region",
    "layout": "merged page-table layout time and fill against painting count (BRKGA vs shelf)",
    "bc1": "the bc1 (DXT1) codec: PSNR and FLIP per painting, sampling cost, hit rate per byte",
    "web": "gigascroll serve's tiles on loopback against aiohttp's static-file handler",
    "exhibition-full": "the paper's 40-painting hall at full size: eight scans, 32 instances",
}


def register(sub) -> None:
    from ..benchmarks import (bc1, cluster, export, gallery, layout, loader, pack, photon,
                              queues, views, walk)
    from ..benchmarks import exhibition_full, foveation, mottle, web

    modules = {"pack": pack, "cluster": cluster, "export": export, "queues": queues,
               "loader": loader, "views": views, "photon": photon, "gallery": gallery,
               "mottle": mottle, "walk": walk, "foveation": foveation, "layout": layout, "bc1": bc1, "web": web,
               "exhibition-full": exhibition_full}
    parser = sub.add_parser("bench", help="run a scenario benchmark")
    whats = parser.add_subparsers(dest="what", metavar="WHAT")
    whats.required = True
    for what, description in BENCHMARKS.items():
        module = modules[what]
        p = whats.add_parser(what, help=description, description=description)
        module.add_arguments(p)
        p.set_defaults(func=module.run)

"""`gigascroll bench web`: `gigascroll serve`'s tiles on loopback against aiohttp's own
static-file handler serving the same tiles as files.

Both servers run in their own process (one each, in turn), the same client load drives them:
`--connections` keep-alive connections from one asyncio client process fetching random tiles
(the same seeded sequence for both) for `--duration` seconds, in alternated rounds. The static peer
serves each tile's bytes (`read_tile`'s) as a file under a temporary directory with
`add_static` (sendfile from the page cache); serve reads the pack through the core reader
(checksums verified) on its thread pool. The first responses are checked against the pack.
Reported: tiles/s and MB/s per server (medians over rounds), serve / static as a ratio, and
serve's batch endpoint (`--batch` tiles a request) under the same load. A first untimed round
of each warms the page cache and the servers' imports. Figures go to
`--out`/results.json under "server" (other parts of the file are kept)."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import pattern_image, write_json

VERIFY_FIRST = 32  # responses per connection compared with the pack's bytes


def add_arguments(p) -> None:
    p.add_argument("--width", type=int, default=16000, help="painting width (default 16000)")
    p.add_argument("--height", type=int, default=2000, help="painting height (default 2000)")
    p.add_argument("--connections", type=int, default=8, help="concurrent connections (default 8)")
    p.add_argument("--duration", type=float, default=5.0, help="seconds per round (default 5)")
    p.add_argument("--rounds", type=int, default=3, help="alternated rounds per server (default 3)")
    p.add_argument("--batch", type=int, default=16, help="tiles per batch request (default 16)")
    p.add_argument("--out", default="bench/web", help="directory of results.json (default bench/web)")
    p.add_argument("--quick", action="store_true", help="tiny sizes and one short round (a smoke run)")
    p.add_argument("--walk-metres", type=float, default=None,
                   help="metres of the client's walk of the scroll room in headless chromium "
                        "(benchmarks/web_walk.py; default 2, with --quick 0; 0 skips it)")


def _tile_files(pack, root: Path) -> list[tuple[int, int, int, int]]:
    """Writes every stored tile's bytes as root/p/l/x/y; returns the keys."""
    keys = []
    for p, painting in enumerate(pack.paintings):
        for level, (nx, ny) in enumerate(painting.level_tiles):
            for x in range(nx):
                d = root / str(p) / str(level) / str(x)
                d.mkdir(parents=True, exist_ok=True)
                for y in range(ny):
                    if pack.has_tile(p, level, x, y):
                        (d / str(y)).write_bytes(pack.read_tile(p, level, x, y).tobytes())
                        keys.append((p, level, x, y))
    return keys


def _start(kind: str, pack_path: Path, files: Path) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen([sys.executable, "-m", "gigascroll.benchmarks.web", "--child", kind,
                             str(pack_path), str(files)], stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if not line.startswith("serving "):
        proc.kill()
        raise RuntimeError(f"the {kind} server did not start")
    return proc, line.split()[1].rstrip("/")


def _stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


async def _load(url: str, paths, expected, batch: int, connections: int, seconds: float, seed: int):
    """(requests, tiles, bytes, seconds, distinct tiles) of `connections` clients fetching
    random tiles."""
    import aiohttp

    rng = np.random.default_rng(seed)
    order = rng.integers(0, len(paths["tile"]), 1 << 20)
    counts, distinct = [0, 0, 0], set()
    conn = aiohttp.TCPConnector(limit=connections, force_close=False)
    async with aiohttp.ClientSession(url, connector=conn) as session:
        deadline = time.perf_counter() + seconds

        async def worker(w: int):
            i, checked = w * 7919, 0
            while time.perf_counter() < deadline:
                if batch:
                    ks = [int(order[(i + j) % len(order)]) for j in range(batch)]
                    i += batch
                    resp = await session.post(paths["batch"], json={"keys": [paths["keys"][k] for k in ks]})
                else:
                    ks = [int(order[i % len(order)])]
                    i += 1
                    resp = await session.get(paths["tile"][ks[0]])
                body = await resp.read()
                if resp.status != 200 or (checked < VERIFY_FIRST
                                          and body != b"".join(expected[k] for k in ks)):
                    raise RuntimeError(f"{url}: wrong response ({resp.status}, {len(body)} bytes)")
                checked += 1
                distinct.update(ks)
                counts[0] += 1
                counts[1] += len(ks)
                counts[2] += len(body)

        t0 = time.perf_counter()
        await asyncio.gather(*(worker(w) for w in range(connections)))
        elapsed = time.perf_counter() - t0
    return counts[0], counts[1], counts[2], elapsed, len(distinct)


def _round(kind, url, keys, expected, h, args, seed) -> dict:
    if kind == "static":
        paths = {"tile": [f"/t/{p}/{l}/{x}/{y}" for p, l, x, y in keys]}
    else:
        paths = {"tile": [f"/api/tiles/{h}/{p}/{l}/{x}/{y}" for p, l, x, y in keys],
                 "batch": f"/api/tiles/{h}/batch", "keys": [list(k) for k in keys]}
    batch = args.batch if kind == "serve-batch" else 0
    n, tiles, nbytes, s, distinct = asyncio.run(_load(url, paths, expected, batch,
                                                      args.connections, args.duration, seed))
    return {"requests_per_s": n / s, "tiles_per_s": tiles / s, "mb_per_s": nbytes / s / 1e6,
            "tiles_fetched": tiles, "distinct_tiles": distinct}


def run(args) -> int:
    from .. import build_pack
    from ..serve import pack_hash

    if args.quick:
        args.width, args.height, args.duration, args.rounds = 2000, 600, 0.5, 1
    if min(args.width, args.height, args.connections, args.rounds, args.batch) < 1 \
            or not 0 < args.duration <= 600 or args.connections > 1024 or args.batch > 64 \
            or args.rounds > 10 or args.width * args.height > 1 << 25:
        raise UserError("--width, --height (at most 2^25 texels), --connections (<= 1024), "
                        "--rounds (<= 10), --batch (<= 64) and --duration (<= 600) must be "
                        "positive")
    walk_metres = (0.0 if args.quick else 2.0) if args.walk_metres is None else args.walk_metres
    if not 0 <= walk_metres <= 10:
        raise UserError("--walk-metres must be in [0, 10] (the scroll is 12 m long)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="gigascroll-bench-web-") as tmp:
        tmp = Path(tmp)
        pack = build_pack(pattern_image(args.width, args.height), tmp / "p.pack")
        keys = _tile_files(pack, tmp / "files")
        expected = [pack.read_tile(*k).tobytes() for k in keys]
        h = pack_hash(pack)
        rows = {"static": [], "serve": [], "serve-batch": []}
        for r in range(0 if args.quick else -1, args.rounds):  # -1: an untimed warm-up
            for kind in ("static", "serve", "serve-batch") if r % 2 == 0 else \
                    ("serve-batch", "serve", "static"):
                proc, url = _start("static" if kind == "static" else "serve", pack.path, tmp / "files")
                try:
                    row = _round(kind, url, keys, expected, h, args, seed=r + 1)
                finally:
                    _stop(proc)
                if r >= 0:
                    rows[kind].append(row)
                print(f"{f'round {r + 1}' if r >= 0 else 'warm-up':8s} {kind:11s}: "
                      f"{row['tiles_per_s']:8.0f} tiles/s {row['mb_per_s']:7.1f} MB/s", flush=True)
    med = {k: {m: statistics.median(x[m] for x in v) for m in v[0]} for k, v in rows.items()}
    result = {"painting": f"{args.width}x{args.height}", "tiles": len(keys),
              "tile_bytes": len(expected[0]), "connections": args.connections,
              "seconds": args.duration, "rounds": args.rounds, "batch": args.batch,
              "cpus": os.cpu_count(), "median": med, "runs": rows,
              "ratio_serve_to_static": med["serve"]["tiles_per_s"] / med["static"]["tiles_per_s"],
              "ratio_batch_to_static": med["serve-batch"]["tiles_per_s"] / med["static"]["tiles_per_s"]}
    print(f"serve / static: {result['ratio_serve_to_static']:.2f} (single tiles), "
          f"{result['ratio_batch_to_static']:.2f} (batches of {args.batch})")
    path = out / "results.json"
    doc = {}
    if path.is_file():
        try:
            doc = json.loads(path.read_text())
        except ValueError:
            doc = {}
    doc["server"] = result
    if walk_metres > 0:  # the client app's walk of the scroll room
        from .web_walk import walk_figures, walk_text

        try:
            doc["client_walk"] = walk_figures(metres=walk_metres)
            print(walk_text(doc["client_walk"]))
        except (RuntimeError, ImportError) as e:  # no chromium or no playwright
            print(f"client walk: not measured ({e})")
    from .web_client import feedback_figures, format_figures  # the virtual texture's part
    try:
        doc["client_feedback"] = (feedback_figures(4000, 1000, frames=20) if args.quick
                                  else feedback_figures(frames=240))
        print(format_figures(doc["client_feedback"]))
    except (RuntimeError, ImportError) as e:  # no chromium or no playwright
        print(f"client feedback: not measured ({e})")
    write_json(path, doc)
    print(f"wrote {path}")
    return 0


def _child(kind: str, pack_path: str, files: str) -> None:
    """A server process of the benchmark: serve's app, or aiohttp's static handler."""
    from aiohttp import web

    from .. import TilePack
    from ..serve import make_app, serve_forever

    if kind == "serve":
        app = make_app(TilePack(pack_path), None)
    else:
        app = web.Application()
        app.router.add_static("/t", files)
    serve_forever(app, "127.0.0.1", 0, announce=lambda url: print(f"serving {url}", flush=True))


if __name__ == "__main__" and len(sys.argv) == 5 and sys.argv[1] == "--child":
    _child(*sys.argv[2:])

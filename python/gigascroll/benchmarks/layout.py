"""`gigascroll bench layout`: merged page-table layout time and fill against painting count,
BRKGA (the default) against the shelf baseline in the same run. Paintings are random sizes
(200..20000 px a side, the default 128-texel tiles with border 4), so their page tables are
the ones a real gallery pack would lay out."""

from __future__ import annotations

import time

import numpy as np

from ..experiments import write_json


def add_arguments(p) -> None:
    p.add_argument("--counts", default="100,500,2000", help="painting counts (comma-separated)")
    p.add_argument("--seed", type=int, default=0, help="random painting sizes' seed")
    p.add_argument("--out", default="build/bench/layout", help="JSON output directory")


def _tables(n: int, seed: int) -> list[tuple[int, int]]:
    from .._core import painting_geometry
    rng = np.random.default_rng(seed)
    return [tuple(painting_geometry(int(w), int(h), 128, 4)["table_size"])
            for w, h in rng.integers(200, 20001, (n, 2))]


def run(args) -> int:
    from ..pack import plan_layout
    try:
        counts = [int(c) for c in args.counts.split(",")]
    except ValueError:
        raise ValueError(f"--counts must be integers separated by commas, got {args.counts!r}") from None
    if not counts or min(counts) < 1 or max(counts) > 100_000:
        raise ValueError("--counts must lie in [1, 100000]")
    rows = []
    for n in counts:
        tables = _tables(n, args.seed)
        row = {"paintings": n}
        for method in ("shelf", "brkga"):
            t0 = time.perf_counter()
            _, _, _, info = plan_layout(tables, method, 0)
            row[f"{method}_s"] = time.perf_counter() - t0
            row[f"{method}_fill"] = info["fill_ratio"]
        rows.append(row)
        print(f"{n:6d} paintings: shelf {row['shelf_s']:7.2f} s fill {row['shelf_fill']:.3f}   "
              f"brkga {row['brkga_s']:7.2f} s fill {row['brkga_fill']:.3f}   "
              f"brkga/shelf time {row['brkga_s'] / max(row['shelf_s'], 1e-9):.1f}x", flush=True)
    from pathlib import Path
    Path(args.out).mkdir(parents=True, exist_ok=True)
    write_json(f"{args.out}/layout.json", {"rows": rows})
    return 0

"""`gigascroll demo`: the built-in painting, synthesized, packed, summarized and previewed."""

from __future__ import annotations

import time
from pathlib import Path


def register(sub) -> None:
    p = sub.add_parser("demo", help="synthesize the built-in painting, pack it and preview it",
                       description="Synthesizes the built-in ink-landscape painting (about a "
                       "minute on 2 cores), builds its tile pack, prints the pack summary and "
                       "writes a PNG preview of a few levels and tiles.")
    p.add_argument("--workdir", default="build/demo", help="output directory (default build/demo)")
    p.add_argument("--width", type=int, default=60000, help="painting width (default 60000)")
    p.add_argument("--height", type=int, default=2400, help="painting height (default 2400)")
    p.add_argument("--seed", type=int, default=0, help="landscape variation (default 0)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..pack import build_pack, pack_summary, synth_painting
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    tif = work / "painting.tif"
    t0 = time.perf_counter()
    synth_painting(tif, args.width, args.height, seed=args.seed, progress=True)
    t1 = time.perf_counter()
    pack = build_pack(tif, work / "painting.pack", force=True, progress=True)
    t2 = time.perf_counter()
    mpx = args.width * args.height / 1e6
    print(pack_summary(pack))
    print(f"synthesized {mpx:.0f} Mpixel in {t1 - t0:.1f} s; packed in {t2 - t1:.1f} s "
          f"({mpx / (t2 - t1):.1f} Mpixel/s)")
    png = work / "preview.png"
    write_preview(pack, png)
    print(f"preview: {png}")
    return 0


def write_preview(pack, png: Path, painting: int = 0) -> None:
    """A matplotlib figure: the painting at a coarse level, the same region at three levels,
    and single tiles with their borders outlined."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    from ..pack import read_level

    p = pack.paintings[painting]
    T, b, P = pack.tile_size, pack.border, pack.payload
    # Coarse overview: the finest level at most 2400 texels wide.
    overview_level = next(l for l, (w, _) in enumerate(p.level_sizes) if w <= 2400)
    overview = read_level(pack, painting, overview_level)

    fig = plt.figure(figsize=(14, 8.2), constrained_layout=True)
    grid = fig.add_gridspec(3, 4, height_ratios=[0.45, 1.3, 1.3])
    ax = fig.add_subplot(grid[0, :])
    ax.imshow(overview, interpolation="lanczos")
    ax.set_title(f"{p.name}: {p.width} x {p.height}, level {overview_level} "
                 f"({overview.shape[1]} x {overview.shape[0]}) of {p.levels}")
    ax.axis("off")

    # One spot seen through three levels: the tile under the middle of the painting.
    cx, cy = p.width // 2, p.height // 2
    for k, level in enumerate([0, 2, 4]):
        if level >= p.levels:
            continue
        tx, ty = (cx >> level) // P, (cy >> level) // P
        tile = pack.read_tile(painting, level, tx, ty)
        ax = fig.add_subplot(grid[1, k])
        ax.imshow(tile, interpolation="nearest")
        ax.add_patch(Rectangle((b - 0.5, b - 0.5), P, P, fill=False, ec="red", lw=1))
        ax.set_title(f"level {level}, tile ({tx}, {ty})\nred: payload, outside: border")
        ax.axis("off")
    # Detail: a 48 x 48 crop of the level-0 tile, showing single-pixel strokes.
    tile0 = pack.read_tile(painting, 0, cx // P, cy // P)
    ax = fig.add_subplot(grid[1, 3])
    ax.imshow(tile0[b:b + 48, b:b + 48], interpolation="nearest")
    ax.set_title("level 0, 48 x 48 texels")
    ax.axis("off")

    # The right end (the seal) at the first levels: the last tile column is clamped at the
    # painting's edge, and each level averages the one above.
    for k, level in enumerate(range(min(4, p.levels))):
        nx, ny = p.level_tiles[level]
        ty = min(ny - 1, int(0.12 * p.level_sizes[level][1]) // P)
        tile = pack.read_tile(painting, level, nx - 1, ty)
        ax = fig.add_subplot(grid[2, k])
        ax.imshow(tile, interpolation="nearest")
        ax.set_title(f"level {level}, right-edge tile ({nx - 1}, {ty})")
        ax.axis("off")
    fig.savefig(png, dpi=90)
    plt.close(fig)

"""`gigascroll demo`: the built-in painting, synthesized, packed, summarized and previewed, then\nthe main job: the walk through the lit scroll room, as video, frames and report."""

from __future__ import annotations

import time
from pathlib import Path


def register(sub) -> None:
    p = sub.add_parser("demo", help="synthesize the built-in painting, pack it, walk the lit gallery",
                       description="Synthesizes the built-in ink-landscape painting (about a "
                       "minute on 2 cores), builds its tile pack, prints the pack summary, "
                       "writes a PNG preview of a few levels and tiles, and walks through the lit "
                       "scroll room (video, frames and report in WORKDIR/walk/).")
    p.add_argument("--workdir", default="gigascroll-demo",
                   help="output directory (default gigascroll-demo in the working directory; "
                        "`make demo` passes build/demo)")
    p.add_argument("--width", type=int, default=60000, help="painting width (default 60000)")
    p.add_argument("--height", type=int, default=2400, help="painting height (default 2400)")
    p.add_argument("--seed", type=int, default=0, help="landscape variation (default 0)")
    p.add_argument("--no-stream", action="store_true", help="skip the streamed-view step")
    p.add_argument("--no-render", action="store_true", help="skip the photon-mapped room")
    p.add_argument("--no-walk", action="store_true", help="skip the gallery walk")
    p.add_argument("--walk-seconds", type=float, default=3.0,
                   help="length of the gallery walk (default 3 s of 90 Hz frames)")
    p.add_argument("--eye", default="720x792", help="per-eye resolution of the walk (default 720x792)")
    from .display_options import add_display_options
    add_display_options(p, "the Cornell box's auto is factor 1")
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
    if not args.no_stream:
        stream_view(pack, work / "streamed_view.png")
    if not args.no_render:
        from .display_options import display_of
        render_room(work / "cornell.png", display_of(args))
    if not args.no_walk:
        gallery_walk(pack, work / "walk", args.eye, args.walk_seconds, args)
    print(f"everything the demo made is in {work.resolve()}/")
    return 0


def gallery_walk(pack, out: Path, eye: str, seconds: float, args=None) -> None:
    """The main job: the walk along the painting in the lit `scroll` room, both eyes streamed
    through the virtual texture with the magnifier, written as video, frames and report."""
    from ..gallery import builtin_room
    from ..walk.record import record_walk
    from ..walk.gallery_walk import GallerySource, GalleryWalk, walk_path
    from .gallery import parse_eye

    w, h = parse_eye(eye)
    room = builtin_room("scroll", pack)
    t0 = time.perf_counter()
    response = None
    if args is not None:
        from .display_options import display_of
        response = display_of(args, room)
    source = GallerySource(room, pack, "baked", photons=1 << 18, response=response)
    print(f"gallery: the scroll room lit in {time.perf_counter() - t0:.1f} s "
          f"({source.light_stats.get('photons_stored', 0)} photons stored, irradiance baked)")
    path = walk_path(room, seconds)
    walk = GalleryWalk(source, pack, path, eye=(w, h))
    res = record_walk(walk, out, settings={"room": "scroll", "eye": f"{w}x{h}",
                                           "seconds": seconds, "lighting": "baked"})
    s = res["summary"]
    from ..walk.frame_rates import fps_text
    print(f"gallery walk: {s['frames']} frames at {w}x{h} per eye, {fps_text(s)} on this "
          f"machine, right eye reusing {100 * s['reused_share']:.0f} % of its pixels, hit rate "
          f"{s['hit_rate']:.3f}, error vs oracle {s['error_mean']:.2g} mean / "
          f"{s['error_final']:.2g} at the end: {out}/walk.mp4, {out}/report.md")


def view_keys(pack, painting: int, level: int, x0: float, x1: float) -> list:
    """Tiles of `level` under the level-0 texel columns [x0, x1) over the painting's height:
    the analytic tile set of a head-on view (the feedback pass computes it by ray casting)."""
    P = pack.payload
    p = pack.paintings[painting]
    nx, ny = p.level_tiles[level]
    t0 = int(x0) >> level
    t1 = (int(x1) - 1) >> level
    return [(painting, level, tx, ty) for tx in range(t0 // P, min(nx - 1, t1 // P) + 1)
            for ty in range(ny)]


def stream_view(pack, png: Path, frames_max: int = 200, per_frame: int = 16) -> None:
    """The run-time pipeline on one head-on view: each ~11 ms frame requests the view's tiles
    from the virtual texture, issues at most `per_frame` loads to the lock-free loader, inserts
    what arrived and samples the view through the page table. Prints the frames until the view
    is sharp and checks the final image against the plain mip chain."""
    import numpy as np

    from ..runtime import MipTexture, TileLoader, VirtualTexture

    p = pack.paintings[0]
    out_w, out_h = 1200, 240
    # The view shows 1/8 of the painting's width around its middle, at about one texel a pixel.
    span = p.width / 8
    x0 = p.width / 2 - span / 2
    level = max(0, min(p.levels - 1, int(np.floor(np.log2(span / out_w)))))
    aspect_h = min(p.height, span * out_h / out_w)
    y0 = (p.height - aspect_h) / 2
    xs = (x0 + (np.arange(out_w) + 0.5) * span / out_w) / p.width
    ys = (y0 + (np.arange(out_h) + 0.5) * aspect_h / out_h) / p.height
    u, v = np.meshgrid(xs, ys)
    keys = view_keys(pack, 0, level, x0, x0 + span)
    vt = VirtualTexture(pack, slots=(30, 30))
    snapshots = []
    with TileLoader(pack, mode="lockfree", threads=1) as loader:
        pending = []
        for frame in range(frames_max):
            t = time.perf_counter()
            missing = vt.request(keys)
            still_missing = set(missing)
            pending = [k for k in pending if k in still_missing]  # issued, not arrived yet
            in_flight = set(pending)
            new = [k for k in missing if k not in in_flight][:max(0, per_frame - len(pending))]
            loader.submit(new)
            pending += new
            vt.drain(loader)
            rgb, answered = vt.sample(0, u, v, lod=level)
            sharp = int(answered.max()) == level  # every pixel answered at the level asked for
            if frame in (0, 2) or sharp:
                snapshots.append((frame, rgb, int(answered.max())))
            if sharp:
                break
            time.sleep(max(0.0, 1 / 90 - (time.perf_counter() - t)))
    reference, _ = MipTexture(pack, 0).sample(u, v, lod=level)
    diff = float(np.abs(rgb - reference).max())
    print(f"streamed view: {len(keys)} tiles of level {level}, sharp after {frame + 1} frames "
          f"(at most {per_frame} loads a frame); max |VT - plain mip texture| = {diff:.2g}")
    from ..outputs import write_image
    strip = np.concatenate([s[1] for s in snapshots], axis=0).clip(0, 255).astype(np.uint8)
    write_image(png, strip)
    print(f"streamed view frames {[s[0] for s in snapshots]} (coarsest answering level "
          f"{[s[2] for s in snapshots]}): {png}")


# The demo's Cornell box: 4 camera samples on a stratified pattern (a straight edge on the
# light) and 16 stratified emitter samples each (one left salt-and-pepper noise on the tall
# block, which sees half the light behind its plane, and in the floor's penumbrae).
DEMO_CORNELL = {"photons": 1 << 20, "spp": 4, "light_samples": 16}


def render_room(png: Path, display=None) -> None:
    """The lighting half: the Cornell box rendered by the Embree photon mapper."""
    from ..photon import builtin_scene, render, save_image

    scene, cam = builtin_scene("cornell", resolution=(256, 256))
    img, stats = render(scene, cam, **DEMO_CORNELL, return_stats=True)
    save_image(png, img, display)
    print(f"photon-mapped Cornell box: {stats['photons_stored']} photons stored, "
          f"{stats['total_seconds']:.2f} s: {png}")


def write_preview(pack, png: Path, painting: int = 0) -> None:
    """A matplotlib figure: the painting at a coarse level, the same region at three levels,
    and single tiles with their borders outlined."""
    from matplotlib.patches import Rectangle

    from ..experiments import pyplot, save_figure
    from ..pack import read_level

    plt = pyplot()
    p = pack.paintings[painting]
    b, P = pack.border, pack.payload
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
    save_figure(fig, png, dpi=90)

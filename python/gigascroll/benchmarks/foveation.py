"""`gigascroll bench foveation`: what fixed foveation of the gallery walk's eyes saves and what
it costs (issue 14 §1).

On poses of the scroll walk in the lit room (baked lighting), with a virtual texture warmed
with every tile either frame asks for (so the error is the foveation's, not streaming's), per
per-eye resolution and in the same run, alternating:

- the display of both eyes (right eye reusing the left eye's hits) with and without
  foveation: wall time (the foveated one includes upsampling and blending) and the primary
  rays traced;
- the feedback pass's distinct tile requests (count and mean level) with and without, and
  the mean requested level of the periphery's camera against the unfoveated eye's;
- the foveated frame's error against the unfoveated frame, separately in the fovea, the
  blend band and the periphery: mean absolute difference and PSNR of the display values
  (the walk's camera response: exposure, neutral curve, sRGB), and the mean FLIP (LDR, at
  the headset's pixels per degree) when flip-evaluator is installed;
- a figure: bench/foveation/error.png (the close look at the largest size).
"""

from __future__ import annotations

import json
import math
import statistics
import time
from pathlib import Path

import numpy as np

from ..experiments import save_figure
from ..outputs import write_text


def add_arguments(p) -> None:
    p.add_argument("--pack", default=None,
                   help="tile pack (default: build/demo/painting.pack, else the built-in painting)")
    p.add_argument("--width", type=int, default=1800,
                   help="per-eye width of the larger size (the headset's 1800 x 1920 aspect); "
                        "the benchmark also runs at half of it")
    p.add_argument("--fovea", type=float, default=30.0, help="fovea angle in degrees")
    p.add_argument("--factor", type=int, default=2, help="periphery density 1/factor per axis")
    p.add_argument("--repeats", type=int, default=2, help="alternated timings per pose")
    p.add_argument("--photons", type=int, default=1 << 17)
    p.add_argument("--out", default="bench/foveation/results.json")
    p.add_argument("--threads", type=int, default=0)


def _levels(keys: np.ndarray) -> np.ndarray:
    from .. import views as v
    k = np.asarray(keys, np.uint64).ravel()
    k = k[k != v.NO_REQUEST]
    return ((k >> np.uint64(32)) & np.uint64(0x1F)).astype(np.float64)


def _distinct(buffers) -> np.ndarray:
    from .. import views as v
    k = np.unique(np.concatenate([b.ravel() for b in buffers]))
    return k[k != v.NO_REQUEST]


def region_errors(reference: np.ndarray, test: np.ndarray, masks: dict, exposure: float,
                  ppd: float | None = None) -> dict:
    """Per region (mask name): mean absolute difference and PSNR (dB) of the display values
    (walk.gallery_walk.tone_map / 255), and the mean FLIP when ppd is given and flip-evaluator is
    installed."""
    from ..walk.gallery_walk import tone_map
    a = tone_map(reference, exposure).astype(np.float32) / 255
    b = tone_map(test, exposure).astype(np.float32) / 255
    flip_map = None
    if ppd is not None:
        try:
            import flip_evaluator
            flip_map = flip_evaluator.evaluate(a, b, "LDR", applyMagma=False,
                                               computeMeanError=False,
                                               parameters={"ppd": float(ppd)})[0]
            flip_map = np.asarray(flip_map).reshape(a.shape[:2] + (-1,))[..., 0]
        except ImportError:
            pass
    out = {}
    d = np.abs(a - b)
    for name, m in masks.items():
        if not m.any():
            continue
        mse = float(np.mean(d[m] ** 2))
        out[name] = {"mad": float(d[m].mean()),
                     "psnr_db": float("inf") if mse == 0 else 10 * math.log10(1 / mse),
                     "pixels": int(m.sum())}
        if flip_map is not None:
            out[name]["flip"] = float(flip_map[m].mean())
    return out, flip_map


def lit_scroll_walk(args):
    from .walk import lit_scroll_walk as walk_scene
    return walk_scene(args)


def run(args) -> int:
    from tqdm import tqdm

    from .. import _core, runtime
    from .. import views as v
    from ..errors import UserError
    from ..walk.foveation import FoveatedDisplay, Foveation
    from ..walk.gallery_walk import parent_keys
    from ..views.exhibition import Headset

    if not 32 <= args.width <= 8192:
        raise UserError(f"--width must be in [32, 8192], got {args.width}")
    if args.repeats < 1:
        raise UserError("--repeats must be >= 1")
    sizes = [(w, round(w * 1920 / 1800)) for w in (args.width // 2, args.width)]
    fov = Foveation(args.fovea, args.factor)
    pack, room, src, path = lit_scroll_walk(args)
    n = len(path)
    # the walk, the first stop and the close look (walk_path's shares: 30 % walk, 15 % stop,
    # 10 % approach, 15 % close look)
    poses = {"walk": int(0.15 * n), "stop": int(0.38 * n), "close look": int(0.62 * n)}
    thr = args.threads
    levels = np.array([t.levels for t in src.tiles], np.int64)
    results = {"pack": str(pack.path), "machine": "2 cores, 24 GB, Debian 12, no GPU, shared",
               "date": time.strftime("%Y-%m-%d"), "fovea_deg": fov.fovea_deg,
               "factor": fov.factor, "blend": fov.blend, "sizes": []}
    figure_data = None
    bar = tqdm(total=len(sizes) * len(poses), unit="pose", desc="foveation")
    for w, h in sizes:
        headset = Headset(width=w, height=h)
        row = {"eye": f"{w}x{h}", "poses": []}
        plain_pass, fd = _core.DisplayPass(), FoveatedDisplay(fov)
        for pose_name, frame in poses.items():
            views = v.frame_cameras(path, frame, headset=headset, magnifier=None)
            lc, rc = views[0][0], views[1][0]
            lay = fov.layout(lc)
            # Feedback with and without foveation: what each would request.
            plain_fb = [src.feedback(c, fw, fh, thr) for c, fw, fh in views]
            fov_views = fov.feedback_views(views, headset.feedback_scale)
            fov_fb = [src.feedback(c, fw, fh, thr) for c, fw, fh in fov_views]
            plain_keys, fov_keys = _distinct(plain_fb), _distinct(fov_fb)
            # fov_fb: left fovea, left periphery, right fovea, right periphery
            per_level = np.concatenate([_levels(fov_fb[1]), _levels(fov_fb[3])]).mean()
            eye_level = np.concatenate([_levels(plain_fb[0]), _levels(plain_fb[1])]).mean()
            fovea_level = np.concatenate([_levels(fov_fb[0]), _levels(fov_fb[2])]).mean()
            # A VT holding every tile either frame reads (requests and trilinear parents).
            vt = runtime.VirtualTexture(pack, (48, 48))
            needed = np.unique(np.concatenate([plain_keys, fov_keys]))
            needed = np.concatenate([needed, parent_keys(needed, levels)])
            missing = vt.request(needed)
            for key in zip(*(a.tolist() for a in v.unpack_requests(missing))):
                vt.insert(key, pack.read_tile(*key))
            if vt.request(needed).size:
                raise RuntimeError("the warmed virtual texture lost tiles (too few slots)")
            # Warm both displays' buffers, then alternate.
            src.display_stereo(plain_pass, vt, lc, rc, True, thr)
            fd.display_stereo(src, vt, lc, rc, True, thr)
            plain_s, fov_s, comp_s = [], [], []
            for _ in range(args.repeats):
                t = time.perf_counter()
                pl, pr = src.display_stereo(plain_pass, vt, lc, rc, True, thr)
                plain_s.append(time.perf_counter() - t)
                t = time.perf_counter()
                fl, fr = fd.display_stereo(src, vt, lc, rc, True, thr)
                fov_s.append(time.perf_counter() - t)
                comp_s.append(fd.left_stats["composite_seconds"]
                              + fd.right_stats["composite_seconds"])
            plain_traced = plain_pass.left_stats["traced"] + plain_pass.right_stats["traced"]
            fov_traced = fd.left_stats["traced"] + fd.right_stats["traced"]
            masks = lay.masks()
            ppd = w / math.degrees(2 * math.atan(lc.tan_half_x))
            err_l, flip_l = region_errors(pl, fl, masks, src.exposure, ppd)
            err_r, _ = region_errors(pr, fr, masks, src.exposure, ppd)
            p = {"pose": pose_name, "frame": frame,
                 "display_ms": 1e3 * statistics.median(plain_s),
                 "foveated_display_ms": 1e3 * statistics.median(fov_s),
                 "composite_ms": 1e3 * statistics.median(comp_s),
                 "time_ratio": statistics.median(fov_s) / statistics.median(plain_s),
                 "rays": int(plain_traced), "foveated_rays": int(fov_traced),
                 "rays_ratio": fov_traced / plain_traced,
                 "left_eye_rays_analytic": [lay.traced_pixels, w * h],
                 "left_eye_rays": [int(fd.left_stats["traced"]),
                                   int(plain_pass.left_stats["traced"])],
                 "requests": int(plain_keys.size), "foveated_requests": int(fov_keys.size),
                 "request_level": float(_levels(plain_keys).mean()),
                 "foveated_request_level": float(_levels(fov_keys).mean()),
                 "eye_sample_level": float(eye_level), "fovea_sample_level": float(fovea_level),
                 "periphery_sample_level": float(per_level),
                 "error_left": err_l, "error_right": err_r}
            row["poses"].append(p)
            if pose_name == "close look":
                figure_data = (pl, fl, flip_l, lay, src.exposure, f"{w}x{h}")
            bar.update(1)
            tqdm.write(
                f"{w}x{h} {pose_name}: display {p['display_ms']:.0f} -> "
                f"{p['foveated_display_ms']:.0f} ms (x{p['time_ratio']:.2f}, composite "
                f"{p['composite_ms']:.0f} ms), rays {plain_traced} -> {fov_traced} "
                f"(x{p['rays_ratio']:.3f}); requests {plain_keys.size} -> {fov_keys.size}, "
                f"mean level {p['request_level']:.2f} -> {p['foveated_request_level']:.2f} "
                f"(periphery samples {per_level:.2f} vs eye {eye_level:.2f}); left error "
                + ", ".join(f"{k} MAD {e['mad']:.4f} PSNR {e['psnr_db']:.1f} dB"
                            + (f" FLIP {e['flip']:.4f}" if "flip" in e else "")
                            for k, e in err_l.items()))
        results["sizes"].append(row)
    bar.close()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, json.dumps(results, indent=1))
    if figure_data is not None:
        fig_path = out.parent / "error.png"
        _figure(fig_path, *figure_data)
        print(f"wrote {fig_path}")
    print(f"wrote {out}")
    return 0


def _figure(path: Path, plain, foveated, flip_map, lay, exposure: float, size: str) -> None:
    """The unfoveated and foveated left eye (fovea and blend band outlined), the FLIP map, and
    crops across the fovea's right edge."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    from ..walk.gallery_walk import tone_map
    a, b = tone_map(plain, exposure), tone_map(foveated, exposure)
    diff = np.abs(a.astype(np.float32) - b.astype(np.float32)).max(axis=2) / 255
    fig, ax = plt.subplots(2, 3, figsize=(15, 10.5))
    for k, (img, title) in enumerate(((a, "unfoveated"), (b, "foveated"))):
        ax[0, k].imshow(img)
        ax[0, k].set_title(f"left eye {size}, {title}")
    ax[0, 1].add_patch(Rectangle((lay.x0, lay.y0), lay.fovea_width, lay.fovea_height,
                                 fill=False, ec="cyan", lw=1))
    band = lay.weight == 1.0
    ys, xs = np.nonzero(band)
    if ys.size:
        ax[0, 1].add_patch(Rectangle((lay.x0 + xs.min(), lay.y0 + ys.min()),
                                     xs.max() - xs.min() + 1, ys.max() - ys.min() + 1,
                                     fill=False, ec="yellow", lw=1, ls="--"))
    if flip_map is not None:
        im = ax[0, 2].imshow(flip_map, cmap="magma", vmin=0, vmax=1)
        ax[0, 2].set_title("FLIP (foveated vs unfoveated)")
    else:
        im = ax[0, 2].imshow(diff, cmap="magma", vmin=0, vmax=0.25)
        ax[0, 2].set_title("|difference| (display units)")
    fig.colorbar(im, ax=ax[0, 2], fraction=0.046)
    # A crop centred on the fovea's right edge, a fifth of the eye wide.
    s = max(16, lay.width // 5)
    cx, cy = lay.x0 + lay.fovea_width, lay.height // 2
    x0, y0 = max(0, cx - s // 2), max(0, cy - s // 2)
    crop = (slice(y0, y0 + s), slice(x0, x0 + s))
    ax[1, 0].imshow(a[crop], interpolation="nearest")
    ax[1, 0].set_title("crop across the fovea's edge: unfoveated")
    ax[1, 1].imshow(b[crop], interpolation="nearest")
    ax[1, 1].set_title("foveated (fovea | band | periphery)")
    im = ax[1, 2].imshow(diff[crop], cmap="magma", vmin=0, vmax=0.25, interpolation="nearest")
    ax[1, 2].set_title("|difference| in the crop")
    fig.colorbar(im, ax=ax[1, 2], fraction=0.046)
    edge = cx - x0
    for k in (0, 1, 2):
        ax[1, k].axvline(edge - 0.5, color="cyan", lw=0.8)
    for row in ax:
        for x in row:
            x.set_xticks([])
            x.set_yticks([])
    fig.tight_layout()
    save_figure(fig, path, dpi=90)

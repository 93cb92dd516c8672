"""What a gallery walk writes: frames (PNG, linear EXR on request), an H.264 MP4 of the walk
(side-by-side stereo), a Markdown report with plots and the results as JSON.

Everything is written into a temporary directory beside the output and renamed into place
when complete, so a failed or interrupted run (SIGTERM included) never leaves a directory that
looks finished; an earlier gallery output there (marked as one) is replaced only then, and
nothing else is ever replaced (gigascroll.outputs' rules).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..outputs import (check_output, has_mark, remove_stale_temps, replace_dir,
                       signals_interrupt, temp_dir, write_image, write_mark, write_text)
from .frame_rates import fps_text
from .video import VideoWriter, check_fps
from .gallery_walk import DISPLAY_PARTS, WALK_STAGES, GalleryWalk, compose_frame

__all__ = ["record_walk", "prepare_output", "is_gallery_output", "MARKER"]

MARKER = "results.json"   # a directory holding it is a complete gallery output


def is_gallery_output(path: Path) -> bool:
    """Whether a directory is a gallery output: marked by the gallery (outputs.MARK), or an
    earlier one's results.json with the gallery's own keys."""
    if has_mark(path, "gallery"):
        return True
    results = path / MARKER
    try:
        if results.is_symlink() or not results.is_file():
            return False
        with open(results, "rb") as f:
            head = f.read(1 << 16).decode("utf-8", "replace")
    except OSError:
        return False
    return head.lstrip().startswith("{") and all(f'"{k}"' in head
                                                 for k in ("settings", "summary", "frames"))


def prepare_output(out: Path) -> Path:
    """Checks that `out` can be written (an existing `out` is an earlier gallery output or
    empty, never a protected place: outputs.check_output) and returns the temporary directory
    to write into, made beside it (its parent is made if need be)."""
    out = Path(out)
    try:
        check_output(out, force=True, directory=True, owned=is_gallery_output,
                     what="a gallery output")
        remove_stale_temps(out, "gallery", hidden=True)  # of runs killed outright
        tmp = temp_dir(out, hidden=True, command="gallery")
        (tmp / "frames").mkdir()
    except OSError as e:
        raise UserError(f"--out {e}") from None
    return tmp


def _commit(tmp: Path, out: Path) -> None:
    replace_dir(tmp, out, owned=is_gallery_output)


def _even(img: np.ndarray) -> np.ndarray:
    """Pads to even width and height (H.264 in yuv420p needs both)."""
    h, w = img.shape[:2]
    return np.pad(img, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") if (h % 2 or w % 2) else img


def _write_png(path: Path, rgb8: np.ndarray) -> None:
    write_image(path, rgb8)


def _write_exr(path: Path, linear: np.ndarray) -> None:
    write_image(path, np.ascontiguousarray(linear, np.float32))


def record_walk(walk: GalleryWalk, out: Path, exr: bool = False, png_every: int | None = None,
                video: bool = True, progress: bool = True, settings: dict | None = None,
                tmp: Path | None = None) -> dict:
    """Runs the walk and writes its frames, video, report and results to `out`. png_every:
    keep every n-th frame as PNG (None: about 40 over the walk, plus the last frame); every
    frame goes into the video. Returns the results dictionary."""
    out = Path(out)
    if video:
        check_fps(walk.path.fps)  # before anything is written
    n = len(walk.path)
    every = png_every or max(1, n // 40)
    if every < 1:
        raise UserError("--png-every must be >= 1")
    tmp = tmp or prepare_output(out)
    display = walk.source.response
    writer = None
    saved: list[str] = []
    with signals_interrupt():  # SIGTERM / SIGHUP: the temporaries go as for Ctrl-C
        try:
            if video:
                w, h = walk.eye
                # x264's frame-packing SEI 3 marks the frames side-by-side stereo (left eye left).
                writer = VideoWriter(tmp / "walk.mp4", (2 * w + (2 * w) % 2, h + h % 2),
                                     walk.path.fps, ["-crf", "20", "-preset", "veryfast",
                                                     "-x264-params", "frame-packing=3"])

            def on_frame(frame, rec, images):
                left, right, mag, lenses = images
                linear = compose_frame(left, right, mag, lenses)
                rgb8 = display.srgb8(linear)
                if writer is not None:
                    writer.send(_even(rgb8))
                if frame % every == 0 or frame == n - 1:
                    name = f"frame_{frame:05d}"
                    _write_png(tmp / "frames" / f"{name}.png", rgb8)
                    saved.append(name)
                    if exr:
                        _write_exr(tmp / "frames" / f"{name}.exr", linear)

            summary = walk.run(progress=progress, on_frame=on_frame)
            if writer is not None:
                w, writer = writer, None
                w.close()
            results = {"settings": settings or {}, "summary": summary, "frames": walk.records,
                       "saved_frames": saved, "source": walk.source.name,
                       "exposure": display.exposure, "display": display.describe(),
                       "light_seconds": getattr(walk.source, "light_seconds", 0.0),
                       "light_stats": _jsonable(getattr(walk.source, "light_stats", {}))}
            _plots(walk.records, summary, tmp)
            _report(results, tmp, video)
            write_mark(tmp, "gallery")
            write_text(tmp / MARKER, json.dumps(_jsonable(results), indent=1))  # last: whole
            _commit(tmp, out)
            return results
        except BaseException:
            if writer is not None:
                writer.abort()
            shutil.rmtree(tmp, ignore_errors=True)
            raise


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, float) and not np.isfinite(x):
        return None
    return x


def _plots(records: list, summary: dict, tmp: Path) -> None:
    from ..experiments import pyplot, save_figure
    plt = pyplot()
    frames = [r["frame"] for r in records]
    parts = [s for s in WALK_STAGES if s != "display"] + [f"display_{p}" for p in DISPLAY_PARTS]
    fig, ax = plt.subplots(figsize=(9, 4), constrained_layout=True)
    ax.stackplot(frames, *[[r[f"{p}_ms"] for r in records] for p in parts],
                 labels=[p.replace("_", " ") for p in parts])
    ax.set_xlabel("frame")
    ax.set_ylabel("ms")
    ax.set_title("per-stage time per frame (display split into rays, reuse, VT sampling, shading)")
    ax.legend(loc="upper left", fontsize=7, ncol=3)
    save_figure(fig, tmp / "stages.png", dpi=90)

    fig, ax = plt.subplots(figsize=(9, 3), constrained_layout=True)
    ax.plot(frames, [1e3 / r["total_ms"] for r in records],
            label="frame loop alone (1 / frame time, no oracle, no recording)")
    wall = np.diff([r["time_s"] for r in records])
    if len(wall):
        ax.plot(frames[1:], 1.0 / np.maximum(wall, 1e-9), color="C1", lw=0.8,
                label="wall clock, with the oracle and recording")
    ax.axhline(90, color="grey", ls="--", lw=0.8, label="90 Hz")
    ax.set_yscale("log")
    ax.set_xlabel("frame")
    ax.set_ylabel("frames per second")
    ax.legend()
    save_figure(fig, tmp / "fps.png", dpi=90)

    fig, ax = plt.subplots(figsize=(9, 3), constrained_layout=True)
    ax.plot(frames, [r["hit_rate"] for r in records], label="hit rate", color="C0")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("frame")
    ax.set_ylabel("hit rate")
    moving = [r["moving"] for r in records]
    for i, m in enumerate(moving):
        if not m:
            ax.axvspan(i - 0.5, i + 0.5, color="0.9", lw=0)
    if "error" in records[0]:
        ax2 = ax.twinx()
        ax2.plot(frames, [r["error"] for r in records], color="C3", label="error vs oracle")
        ax2.set_ylabel("mean |frame - oracle| (display units)", color="C3")
    ax.set_title("hit rate and error against the all-resident oracle (grey: camera still)")
    save_figure(fig, tmp / "hit_error.png", dpi=90)

    stops = summary.get("stops", [])
    fig, ax = plt.subplots(figsize=(6, 3), constrained_layout=True)
    if stops:
        xs = np.arange(len(stops))
        lat = [s["display_latency_frames"] or 0 for s in stops]
        ex = [s["exact_after_frames"] or 0 for s in stops]
        ax.bar(xs - 0.2, lat, 0.4, label="all requests resident")
        ax.bar(xs + 0.2, ex, 0.4, label="frame = oracle")
        ax.set_xticks(xs, [f"stop {i + 1}\n(frame {s['first_frame']})" for i, s in enumerate(stops)])
        ax.axhline(2, color="grey", ls="--", lw=0.8, label="2 frames")
        ax.legend(fontsize=8)
    ax.set_ylabel("frames after the stop")
    ax.set_title("display latency after each stop")
    save_figure(fig, tmp / "latency.png", dpi=90)


def _report(results: dict, tmp: Path, video: bool) -> None:
    s = results["summary"]
    st = results["settings"]
    lines = [f"# Gallery walk: {results['source']}", ""]
    if st:
        lines += ["Settings: " + ", ".join(f"{k} = {v}" for k, v in st.items()), ""]
    ms = lambda k: f"{s[k]:.2f}"  # noqa: E731
    lines += [
        f"{s['frames']} frames at {s['eye'][0]} x {s['eye'][1]} per eye: {fps_text(s)} (the "
        f"path runs at {s['path_fps']:g} Hz). The first is 1000 / the mean frame time (the "
        "stages below); the second counts wall-clock time from the first frame to the last, "
        "so it also pays for " + ("the oracle comparison and " if "oracle_ms" in s else "") +
        "composing, encoding and saving each frame (results.json: `fps_from_frame_time` and "
        "`fps`, explained in `fps_meaning`). "
        f"Lighting took {results['light_seconds']:.1f} s once, before the walk. "
        f"{_display_text(results.get('display'))}", "",
        "| stage | mean ms / frame |", "|---|---|",
        *[f"| {k} | {ms(k + '_ms')} |" for k in WALK_STAGES],
        *[f"| display: {p} | {ms('display_' + p + '_ms')} |" for p in DISPLAY_PARTS],
        f"| left eye display | {ms('left_display_ms')} |",
        f"| right eye display (reusing {100 * s['reused_share']:.0f} % of its pixels) | "
        f"{ms('right_display_ms')} |",
        *([f"| oracle comparison (not in the frame loop) | {ms('oracle_ms')} |"]
          if "oracle_ms" in s else []), "",
        f"Mean hit rate {s['hit_rate']:.3f}, {s['requests_per_frame']:.0f} distinct requests a "
        "frame." + (f" Mean error against the oracle {s['error_mean']:.4g}, last frame "
                    f"{s['error_final']:.4g} (mean absolute difference in display units)."
                    if "error_mean" in s else ""), "",
        "| stop | first frame | frames still | display latency (frames) | equal to oracle after |",
        "|---|---|---|---|---|",
        *[f"| {i + 1} | {x['first_frame']} | {x['frames']} | {x['display_latency_frames']} | "
          f"{x['exact_after_frames']} |" for i, x in enumerate(s["stops"])], "",
        "![stage times](stages.png)", "", "![fps](fps.png)", "",
        "![hit rate and error](hit_error.png)", "", "![latency](latency.png)", ""]
    if video:
        lines += ["The walk as video (side-by-side stereo, left eye left): [walk.mp4](walk.mp4)", ""]
    saved = results["saved_frames"]
    pick = sorted({saved[0], saved[len(saved) // 3], saved[2 * len(saved) // 3], saved[-1]}) \
        if saved else []
    for name in pick:
        lines += [f"Frame {int(name.split('_')[1])}:", "", f"![{name}](frames/{name}.png)", ""]
    write_text(tmp / "report.md", "\n".join(lines))


def _display_text(d: dict | None) -> str:
    """The report's sentence on the camera response the frames went through."""
    if not d:
        return ""
    return (f"Frames shown at EV100 {d['ev100']:.2f} (exposure factor {d['exposure']:.4g}, "
            f"{d['how']}), tone curve {d['tone']}, sRGB; a white painting at "
            f"{d['white_lux'] or 0:.4g} lux is exposed to {d['paper_white']:g}."
            if d.get("white_lux") else
            f"Frames shown at EV100 {d['ev100']:.2f} (exposure factor {d['exposure']:.4g}), "
            f"tone curve {d['tone']}, sRGB.")

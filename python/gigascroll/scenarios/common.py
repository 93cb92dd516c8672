"""What every scenario shares beyond gigascroll.experiments: options, the test packs and
camera paths a run uses (its own, built once into the cache directory, or the user's), loop
runs and their rows and checks, and the report (results JSON, matplotlib plots, Markdown,
PNG frames)."""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import views as v
from ..experiments import (cached_pack, pattern_image, pyplot, save_figure, scroll_pack, spec_of,
                           write_json)
from ..walk.frame_loop import STAGES, FrameLoop
from ..outputs import write_bytes, write_text
from ..pack import TilePack
from ..views.baselines import LodMapping

# The scaled-down painting of the quick single-scroll runs: 0.95 m x 12.6 cm at the scroll's
# texel size.
QUICK_SIZE = (12000, 1600)


@dataclass
class Options:
    quick: bool = False
    out: Path = Path("scenario-out")
    cache: Path | None = None     # where packs are kept between runs (default: out/cache)
    threshold: int = 16           # direct loading: tiles per frame (VT-mobile-VR: 16)
    methods: tuple[str, ...] | None = None
    pack: Path | None = None      # use this pack instead of building one
    path: Path | None = None      # camera path JSON instead of the scenario's own
    threads: int = 0
    pace: bool = True
    duration: float | None = None  # seconds of camera motion in full runs (scenario default)

    def __post_init__(self):
        if self.duration is not None and not (math.isfinite(self.duration) and
                                              self.duration > 0):
            raise ValueError(f"duration must be a positive number of seconds, got "
                             f"{self.duration!r}")
        if not (isinstance(self.threshold, int) and self.threshold > 0):
            raise ValueError(f"the loading threshold must be a positive integer, got "
                             f"{self.threshold!r}")
        self.out = Path(self.out)
        if self.cache is None:
            self.cache = self.out / "cache"
        self.cache = Path(self.cache)


def open_user_pack(opts: Options) -> TilePack:
    if not Path(opts.pack).exists():
        raise OSError(f"{opts.pack}: no such pack")
    return TilePack(str(opts.pack))


def pattern_pack(opts: Options, width: int, height: int) -> TilePack:
    """The user's pack, or a cached pack of one pattern painting of width x height."""
    if opts.pack:
        return open_user_pack(opts)
    return cached_pack(opts.cache, f"pattern-{width}x{height}-raw",
                       lambda: [pattern_image(width, height)], progress=not opts.quick)


def scroll_room(opts: Options) -> tuple[v.Exhibition, TilePack]:
    """The single-scroll room and its pack: the quick pattern painting (QUICK_SIZE) or, in a
    full run, the full scroll (synthesized and packed on first use); --pack replaces it."""
    if opts.quick:
        return v.single_scroll(spec_of("pattern", *QUICK_SIZE)), pattern_pack(opts, *QUICK_SIZE)
    pack = open_user_pack(opts) if opts.pack else scroll_pack(opts.cache)
    return v.single_scroll(), pack


def user_path(opts: Options, default: v.CameraPath, exhibition: v.Exhibition) -> v.CameraPath:
    if opts.path is None:
        return default
    if not Path(opts.path).exists():
        raise OSError(f"{opts.path}: no such camera path file")
    return v.CameraPath.load(opts.path)


def check_methods(opts: Options, allowed: tuple[str, ...], default: tuple[str, ...]):
    methods = opts.methods or default
    bad = [m for m in methods if m not in allowed]
    if bad:
        raise ValueError(f"unknown method {bad[0]!r} for this scenario; choose from "
                         f"{', '.join(allowed)}")
    return tuple(methods)


def frame_loop(opts: Options, ex: v.Exhibition, pack, path: v.CameraPath,
               per_frame: int | None = None, **kw) -> FrameLoop:
    """A frame loop with the run's threshold and threads. Quick runs wait for each frame's
    loads (deterministic invariants); full runs are paced at 90 Hz with the loader draining
    whatever is ready."""
    return FrameLoop(ex, pack, path, per_frame=opts.threshold if per_frame is None else per_frame,
                     pace=opts.pace and not opts.quick, wait_loads=opts.quick,
                     threads=opts.threads, **kw)


def lod_slots(ex: v.Exhibition, path: v.CameraPath, frame: int = 0) -> tuple[int, int]:
    """Cache slots that hold the whole levels LOD mapping picks (its memory)."""
    lod = LodMapping(ex)
    n = sum(pl[1].tile_count(lv) for pl, lv in zip(lod.paintings, lod.chosen_levels(path, frame)))
    n += sum(t.levels for t in ex.tiles) + 64
    side = max(30, math.isqrt(n) + 1)
    return side, side


def methods_agree(ex: v.Exhibition, path: v.CameraPath, frames=(0, -1), threads: int = 0) -> bool:
    """The four processing methods give the same three sets on the same buffers (the
    reference residency with the coarsest tiles resident)."""
    resident = ex.resident_set()
    for f in frames:
        f = f % len(path)
        bufs = v.feedback_buffers(ex, path, f, threads=threads)
        sets = [v.run_processor(v.make_processor(m, ex.tiles, threads), bufs, resident, f)
                for m in v.PROCESSING_METHODS]
        for s in sets[1:]:
            for k in ("requests", "responses", "commands"):
                if not np.array_equal(np.sort(s[k]), np.sort(sets[0][k])):
                    return False
    return True


def loop_row(loop, summary: dict, **extra) -> dict:
    """One result row: the loop's summary plus its per-frame records (JSON-safe)."""
    row = dict(extra)
    row.update({k: _safe(x) for k, x in summary.items()})
    row["records"] = [{k: _safe(x) for k, x in r.items()} for r in loop.records]
    return row


def loading_checks(rows: list[dict], threshold: int, quick: bool) -> dict:
    """Direct loading never issues more than the threshold a frame; in quick (waiting) runs
    every issued tile arrives: nothing is lost between the command queue and the cache."""
    checks = {"issue_within_threshold": all(x["issued"] <= threshold
                                            for r in rows for x in r["records"])}
    if quick:
        checks["nothing_lost_in_loading"] = all(
            sum(x["loaded"] for x in r["records"]) == sum(x["issued"] for x in r["records"])
            for r in rows)
    return checks


def _safe(x):
    if isinstance(x, (np.floating, float)):
        return None if not math.isfinite(float(x)) else float(x)
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, (list, tuple)):
        return [_safe(y) for y in x]
    return x


def save_png(path: Path, rgb: np.ndarray) -> None:
    import matplotlib.pyplot as plt
    img = np.asarray(rgb, np.float32)
    if img.size and img.max() > 1.0 + 1e-6:  # 0..255 colours
        img = img / 255.0
    img = np.clip(img, 0, 1)
    buf = io.BytesIO()  # encoded in memory, written atomically (no truncated PNG on a full disk)
    plt.imsave(buf, img, format="png")
    write_bytes(path, buf.getvalue())


@dataclass
class Report:
    name: str
    out: Path
    title: str
    lines: list = field(default_factory=list)
    results: dict = field(default_factory=dict)

    def text(self, s: str = "") -> None:
        self.lines.append(s)

    def table(self, header: list[str], rows: list[list]) -> None:
        self.lines.append("| " + " | ".join(header) + " |")
        self.lines.append("|" + "---|" * len(header))
        for r in rows:
            self.lines.append("| " + " | ".join(_fmt(c) for c in r) + " |")
        self.lines.append("")

    def figure(self, fig, file: str, caption: str) -> None:
        save_figure(fig, self.out / file, dpi=110, bbox_inches="tight")
        self.lines.append(f"![{caption}]({file})\n")

    def hit_rate_figure(self, rows: list[dict], labels: list[str], file: str,
                        caption: str) -> None:
        """The hit rate per frame of each row's loop."""
        fig, ax = pyplot().subplots(figsize=(7, 3.2))
        for r, label in zip(rows, labels):
            ax.plot([f["hit_rate"] for f in r["records"]], label=label)
        ax.set_xlabel("frame")
        ax.set_ylabel("hit rate")
        ax.legend(fontsize=7)
        self.figure(fig, file, caption)

    def stage_table(self, header: str, rows: list[dict], labels: list) -> None:
        """Each row's mean stage times per frame (ms) and their total."""
        self.table([header, *STAGES, "total"],
                   [[label, *[r[f"{s}_ms"] for s in STAGES], sum(r[f"{s}_ms"] for s in STAGES)]
                    for r, label in zip(rows, labels)])

    def checks(self, checks: dict) -> None:
        self.text("## Invariants\n")
        self.table(["check", "holds"], [[k, ok] for k, ok in checks.items()])

    def image(self, rgb: np.ndarray, file: str, caption: str) -> None:
        save_png(self.out / file, rgb)
        self.lines.append(f"![{caption}]({file})\n")

    def finish(self, checks: dict, report, *args) -> dict:
        """The end of every scenario: its invariants into the results, the report's body by
        report(self, results, *args), then both files written; returns the results."""
        self.results["checks"] = checks
        report(self, self.results, *args)
        self.write()
        return self.results

    def write(self) -> Path:
        self.out.mkdir(parents=True, exist_ok=True)
        # Results first, report last: a report on disk means the run completed.
        write_json(self.out / f"{self.name}.json", self.results, indent=1)
        md = self.out / f"{self.name}.md"
        write_text(md, f"# {self.title}\n\n" + "\n".join(self.lines) + "\n")
        return md


def _fmt(c) -> str:
    if c is None:
        return "-"
    if isinstance(c, float):
        return f"{c:.3g}" if abs(c) < 1000 else f"{c:.0f}"
    return str(c)

"""What every scenario shares: test paintings and their packs (built once into a cache
directory), loop runs, and the report (results JSON, matplotlib plots, Markdown, PNG frames)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import views as v

TEXEL_M = v.SCROLL.width_m / v.SCROLL.width  # every painting at the scroll's 78.9 um/texel


@dataclass
class Options:
    quick: bool = False
    out: Path = Path("scenario-out")
    cache: Path | None = None     # where packs are kept between runs (default: out/cache)
    threshold: int = 16           # direct loading: tiles per frame (seed 000: 16)
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


def pattern_image(width: int, height: int, seed: int = 0) -> np.ndarray:
    """A cheap synthetic painting whose every tile differs (the loop measures loading and
    sampling, not the picture)."""
    yy = np.arange(height, dtype=np.int32)[:, None]
    xx = np.arange(width, dtype=np.int32)[None, :]
    img = np.empty((height, width, 3), np.uint8)
    img[..., 0] = (xx * 7 + yy + seed * 31) % 256
    img[..., 1] = (xx // 3 + yy * 5) % 256
    img[..., 2] = ((xx >> 2) ^ (yy >> 2)) % 256
    return img


def cached_pack(opts: Options, key: str, images):
    """Opens pack `key` from the cache, or builds it from `images()` (a callable returning a
    list of arrays or image paths). A build goes into a temporary directory renamed at the
    end, so an interrupted run leaves no pack that looks complete."""
    from .. import pack as pk
    path = opts.cache / f"{key}.pack"
    if path.exists():
        try:
            return pk.TilePack(str(path))
        except (OSError, ValueError) as e:
            raise OSError(f"{path}: cached pack is unreadable ({e}); delete it to rebuild") \
                from None
    opts.cache.mkdir(parents=True, exist_ok=True)
    return pk.build_pack(images(), path, progress=not opts.quick)


def scroll_pack(opts: Options):
    """The full 152089 x 6083 built-in ink landscape (seed 000's scroll), synthesized and
    packed on first use (several minutes), then read from the cache."""
    from .. import pack as pk
    w, h = v.SCROLL.width, v.SCROLL.height

    def images():
        tif = opts.cache / f"ink-{w}x{h}-s0.tif"
        if not tif.exists():
            pk.synth_painting(tif, w, h, seed=0, progress=True)
        return [str(tif)]
    return cached_pack(opts, f"ink-{w}x{h}-s0-raw", images)


def spec_of(name: str, width: int, height: int) -> v.PaintingSpec:
    return v.PaintingSpec(name, width, height, width * TEXEL_M, height * TEXEL_M)


def open_user_pack(opts: Options):
    from .. import pack as pk
    if not Path(opts.pack).exists():
        raise OSError(f"{opts.pack}: no such pack")
    return pk.TilePack(str(opts.pack))


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
    plt.imsave(path, img)


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
        fig.savefig(self.out / file, dpi=110, bbox_inches="tight")
        import matplotlib.pyplot as plt
        plt.close(fig)
        self.lines.append(f"![{caption}]({file})\n")

    def image(self, rgb: np.ndarray, file: str, caption: str) -> None:
        save_png(self.out / file, rgb)
        self.lines.append(f"![{caption}]({file})\n")

    def write(self) -> Path:
        self.out.mkdir(parents=True, exist_ok=True)
        # Results first, report last: a report on disk means the run completed.
        tmp = self.out / f"{self.name}.json.tmp"
        tmp.write_text(json.dumps(self.results, indent=1))
        os.replace(tmp, self.out / f"{self.name}.json")
        md = self.out / f"{self.name}.md"
        md.write_text(f"# {self.title}\n\n" + "\n".join(self.lines) + "\n")
        return md


def _fmt(c) -> str:
    if c is None:
        return "-"
    if isinstance(c, float):
        return f"{c:.3g}" if abs(c) < 1000 else f"{c:.0f}"
    return str(c)

"""Building tile packs: the merged page-table layout and the streamed build of one pack
from images (format in README.md and the core's pack/format.h). A build goes into a
temporary sibling directory renamed into place at the end.

A build may also run as shards (build_pack(..., workers=N) or scheduler=ADDRESS): each
painting is built by a worker of a Dask cluster (or of a plain process pool) into its own
tile file and shard index, exactly the bytes a single-process build writes for it; the layout
runs once on the paintings' sizes and a final step writes index.bin and the manifest and
renames the pack into place. Shards live in `OUT.shards/` until then, so a failed build
leaves no pack and `resume=True` reuses the shards that were completed and verify."""

from __future__ import annotations

import json
import os
import re
import shutil
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import _core
from .._core import TilePack, painting_geometry
from .cluster import check_timeout, scheduler_location
from .colour import plan_colour
from .images import ImageSource, open_image, require_utf8_path
from ..outputs import (Interrupted, check_output, remove_stale_temps, replace_dir,
                       signals_interrupt, temp_dir)
from .shards import build_sharded, feed

__all__ = ["build_pack", "plan_layout", "MANIFEST", "BuildInterrupted"]

MANIFEST = "manifest.json"


# ----------------------------------------------------------------------------- layout

def plan_layout(table_sizes: Sequence[tuple[int, int]], method: str = "brkga", seed: int = 0):
    """Places the paintings' power-of-two page tables (Mp, Np) in one merged power-of-two
    table, each at offsets that are multiples of its own size (so eqs 5, 6 stay exact).
    Returns (table_width, table_height, offsets, info); info holds both packers' fill ratios
    (BRKGA and the shelf baseline), whichever `method` was chosen."""
    if method not in ("brkga", "shelf"):
        raise ValueError(f"unknown layout method '{method}' (expected brkga or shelf)")
    return _core.layout_page_tables([(int(w), int(h)) for w, h in table_sizes], method, seed)


# ----------------------------------------------------------------------------- building

# The files a pack directory holds: --force replaces a directory only if it holds nothing else
# and its manifest says it is a pack (a source tree with a manifest.json is not one).
PACK_FILES = frozenset({MANIFEST, "tiles.bin", "index.bin"})
_TILE_FILE = re.compile(r"tiles-\d{5}\.bin")


def _is_pack_dir(path: Path) -> bool:
    names = {p.name for p in path.iterdir()}
    manifest = path / MANIFEST
    names = {n for n in names if not _TILE_FILE.fullmatch(n)}
    if not names <= PACK_FILES or not manifest.is_file() or manifest.is_symlink():
        return False
    try:
        m = json.loads(manifest.read_text())
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return False
    return isinstance(m, dict) and m.get("format") == "gigascroll-pack"


def _prepare_output(out: Path, force: bool) -> None:
    check_output(out, force=force, directory=True, owned=_is_pack_dir, what="a tile pack")


# ----------------------------------------------------------------------------- files on disk

# A build stopped by SIGTERM or SIGHUP (SIGINT stays a plain KeyboardInterrupt); its temporary
# directory has been removed. `signum` is the signal's number.
BuildInterrupted = Interrupted
_signals_interrupt = signals_interrupt


def _only_pack_files(path: Path) -> bool:
    """Whether a directory holds nothing but what a build writes (a pack's files, finished
    or not): a leftover that provably is a build's."""
    try:
        return all(p.name in PACK_FILES or _TILE_FILE.fullmatch(p.name) for p in path.iterdir())
    except OSError:
        return False


def _remove_stale_tmp(out: Path) -> list[Path]:
    """Removes `OUT.tmp-<pid>` siblings of `out` left by builds whose process is gone
    (SIGKILL, power loss) and holding only pack files; a live process' build directory is
    left alone. Returns them."""
    return remove_stale_temps(out, None, belongs=_only_pack_files)
    for p in siblings:
        m = pattern.fullmatch(p.name)
        if (m and int(m.group(1)) != os.getpid() and _process_gone(int(m.group(1)))
                and p.is_dir() and not p.is_symlink() and _only_pack_files(p)):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


def build_pack(inputs, out, tile_size: int = 128, border: int = 4, codec: str = "raw", *,
               force: bool = False, names: Sequence[str] | None = None, layout: str = "brkga",
               seed: int = 0, threads: int = 0, zstd_level: int = 3, bc1_fit: str = "range",
               progress: bool = False,
               band_rows: int = 0, colour: str = "convert", intent: str = "relative",
               black_point_compensation: bool = True, workers: int = 0,
               scheduler: str | None = None, executor: str = "dask", resume: bool = False,
               shard_hook: Callable[[int, str], None] | None = None,
               timeout: float | None = None, instances=None) -> TilePack:
    """Builds a tile pack at `out` from one image or a list of images (file paths or numpy
    arrays, one painting each) and returns it opened. The build goes into a temporary sibling
    directory renamed into place at the end, so a failed or interrupted build leaves nothing
    that opens as a pack. Colours (see .colour): `colour="convert"` turns an embedded ICC
    profile (or EXR chromaticities) into sRGB with the rendering `intent`; "keep" stores the
    values untouched; either way the manifest records what was done. `codec="bc1"` stores
    DXT1 blocks (libsquish's `bc1_fit`: "range", fast, or "cluster", ~1.4 dB better at ~25x
    the encoding time), which the cache keeps compressed.

    Sharded builds: `workers=N` builds each painting on one of N workers of a Dask
    LocalCluster (`scheduler="tcp://HOST:PORT"`: on that cluster's workers, which must see
    `out`'s directory), or with `executor="processes"` of a plain process pool; the pack is
    the same bytes as a single-process build. `resume=True` reuses the verified shards a
    failed sharded build left in `OUT.shards/`. `threads` is per worker there (default 1).
    `timeout` bounds each wait on Dask, in seconds: connecting to the scheduler (default
    30), its first worker and any stretch without workers (default 60); each ends in an
    OSError naming the address and what it waited for. Only tcp:// addresses are supported.
    `shard_hook(index, name)`, if given, runs on the worker before each painting (tests).

    Instances: `instances=[(name, source), ...]` adds, after the inputs' paintings, paintings
    that share an input's tiles (`source`: its index or painting name): each has its own name
    and page-table placement but no tile data of its own, so copies of one scan cost one
    scan's disk. Without instances the pack is byte for byte what it was before they existed."""
    if isinstance(inputs, (str, os.PathLike, np.ndarray)):
        inputs = [inputs]
    inputs = list(inputs)
    if not inputs:
        raise ValueError("no input images")
    if codec not in ("raw", "zstd", "bc1"):
        raise ValueError(f"unknown codec '{codec}' (expected raw, zstd or bc1)")
    if not (isinstance(tile_size, (int, np.integer)) and isinstance(border, (int, np.integer))):
        raise ValueError("tile_size and border must be integers")
    if border < 0 or tile_size <= 2 * border:
        raise ValueError(f"tile_size ({tile_size}) must be larger than 2 * border ({2 * border})")
    if bc1_fit not in ("range", "cluster"):
        raise ValueError(f"bc1_fit must be 'range' or 'cluster', got '{bc1_fit}'")
    if codec == "bc1" and (tile_size % 4 or (tile_size - 2 * border) % 4):
        raise ValueError(f"bc1 needs tile_size and payload (tile_size - 2 border) to be multiples "
                         f"of 4, got {tile_size} and {tile_size - 2 * border}")
    if names is not None and len(names) != len(inputs):
        raise ValueError("names must have one entry per input")
    if len(inputs) > _core.MAX_PACK_PAINTINGS:
        raise ValueError(f"{len(inputs)} images: a pack holds at most "
                         f"{_core.MAX_PACK_PAINTINGS} paintings (the tile key's 16-bit field)")
    if (not isinstance(workers, (int, np.integer)) or isinstance(workers, bool)
            or not 0 <= workers <= 4096):
        raise ValueError(f"workers must be an integer in [0, 4096], got {workers!r}")
    if executor not in ("dask", "processes"):
        raise ValueError(f"unknown executor '{executor}' (expected dask or processes)")
    sharded = bool(workers) or scheduler is not None
    timeout = check_timeout(timeout)
    if scheduler is not None:
        scheduler_location(scheduler)  # an unsupported address: now, before any work
    if resume and not sharded:
        raise ValueError("resume needs a sharded build (workers or scheduler)")
    out = Path(out)
    require_utf8_path(out.absolute())
    if names is not None:
        for n in names:
            if not isinstance(n, str) or "\0" in n or any(0xD800 <= ord(c) <= 0xDFFF for c in n):
                raise ValueError(f"painting name {n!r} is not a valid UTF-8 text")
    instances = _check_instances(instances, len(inputs))
    colour_options = {"mode": colour, "intent": intent,
                      "black_point_compensation": black_point_compensation}
    plan_colour("build_pack", 3, **colour_options)  # unknown mode / intent: now
    _prepare_output(out, force)
    _remove_stale_tmp(out)
    with _signals_interrupt():
        return _build(inputs, out, tile_size, border, codec, names, layout, seed, threads,
                      zstd_level, progress, band_rows, colour_options,
                      dict(sharded=sharded, workers=workers, scheduler=scheduler,
                           executor=executor, resume=resume, hook=shard_hook,
                           timeout=timeout), bc1_fit, instances)


def _check_instances(instances, n_inputs: int) -> list[tuple[str, int | str]]:
    """[(name, source)] with each source an input index in range or a name (resolved once the
    inputs are open); ValueError for anything else."""
    if instances is None:
        return []
    if isinstance(instances, (str, bytes, dict)):
        raise ValueError("instances must be a list of (name, source) pairs")
    try:
        items = list(instances)
    except TypeError:
        raise ValueError(f"instances must be a list of (name, source) pairs, not "
                         f"{type(instances).__name__}") from None
    out = []
    for item in items:
        if not (isinstance(item, (tuple, list)) and len(item) == 2):
            raise ValueError(f"instance {item!r} is not a (name, source) pair")
        name, source = item
        if not isinstance(name, str) or not name or "\0" in name \
                or any(0xD800 <= ord(c) <= 0xDFFF for c in name):
            raise ValueError(f"instance name {name!r} is not a non-empty UTF-8 text")
        if isinstance(source, (int, np.integer)) and not isinstance(source, bool):
            if not 0 <= source < n_inputs:
                raise ValueError(f"instance '{name}': source {source} is not an input index "
                                 f"(there are {n_inputs} inputs)")
            source = int(source)
        elif not isinstance(source, str):
            raise ValueError(f"instance '{name}': source must be an input's index or name, "
                             f"not {type(source).__name__}")
        out.append((name, source))
    if n_inputs + len(out) > _core.MAX_PACK_PAINTINGS:
        raise ValueError(f"{n_inputs + len(out)} paintings: a pack holds at most "
                         f"{_core.MAX_PACK_PAINTINGS} (the tile key's 16-bit field)")
    return out


def _resolve_instances(instances, sources) -> list[tuple[str, int]]:
    """Sources as input indices (a name is an input painting's); names unique among all."""
    index = {s.name: i for i, s in enumerate(sources)}
    used = set(index)
    out = []
    for name, source in instances:
        if isinstance(source, str):
            if source not in index:
                raise ValueError(f"instance '{name}': no input painting named '{source}' "
                                 f"(they are: {', '.join(list(index)[:10])})")
            source = index[source]
        if name in used:
            raise ValueError(f"instance name '{name}' is already a painting's name")
        used.add(name)
        out.append((name, source))
    return out


def _mpx_bar():
    """tqdm counting Mpixels whose updates stop at the total: the float sum of the bands' shares
    may pass it by a rounding error, which tqdm warns about (TqdmWarning, under 1 Mpixel)."""
    from tqdm import tqdm

    class MpxBar(tqdm):
        def update(self, n=1):
            return super().update(min(n, max(0.0, self.total - self.n)))
    return MpxBar


def _build(inputs, out, tile_size, border, codec, names, layout, seed, threads, zstd_level,
           progress, band_rows, colour_options, sharding, bc1_fit, instances) -> TilePack:
    sources: list[ImageSource] = []
    bar = None
    tmp = None
    try:
        for i, image in enumerate(inputs):
            name = names[i] if names else (None if not isinstance(image, np.ndarray) else
                                           f"painting{i}" if len(inputs) > 1 else "painting")
            sources.append(open_image(image, name, band_rows, colour_options))
        used = set()
        for s in sources:  # unique names
            base, k = s.name, 1
            while s.name in used:
                k += 1
                s.name = f"{base}-{k}"
            used.add(s.name)
        instances = _resolve_instances(instances, sources)
        geoms = [painting_geometry(s.width, s.height, tile_size, border) for s in sources]
        sizes = [g["table_size"] for g in geoms] + [geoms[i]["table_size"] for _, i in instances]
        table_w, table_h, offsets, info = plan_layout(sizes, layout, seed)
        placed = [(name, i, *offsets[len(sources) + k]) for k, (name, i) in enumerate(instances)]
        offsets = offsets[:len(sources)]
        if sharding["sharded"]:
            for s in sources:  # the workers open their own
                s.close()
            opts = {"tile_size": int(tile_size), "border": int(border), "codec": codec,
                    "zstd_level": int(zstd_level), "bc1_fit": bc1_fit, "threads": int(threads) or 1,
                    "band_rows": int(band_rows), "colour": colour_options}
            build_sharded(inputs, sources, offsets, (table_w, table_h), info, out, opts,
                          workers=int(sharding["workers"]), scheduler=sharding["scheduler"],
                          executor=sharding["executor"], resume=sharding["resume"],
                          progress=progress, hook=sharding["hook"], owned=_is_pack_dir,
                          timeout=sharding["timeout"], instances=placed)
            return TilePack(out)

        tmp = temp_dir(out)
        builder = _core.PackBuilder(tmp, tile_size, border, codec, zstd_level, threads, bc1_fit)
        total = sum(s.width * s.height for s in sources)
        if progress:
            bar = _mpx_bar()(total=total / 1e6, unit="Mpx", unit_scale=False, desc="pack",
                       bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} Mpx [{elapsed}<{remaining},"
                                  " {rate_fmt}]")
        for s, (ox, oy) in zip(sources, offsets):
            builder.begin_painting(s.name, s.width, s.height, s.source, s.conversion, ox, oy,
                                   "" if s.colour is None else json.dumps(s.colour))
            feed(builder, s, bar)
            builder.end_painting()
            s.close()
        for name, i, ox, oy in placed:
            builder.add_instance(name, i, ox, oy)
        builder.finish(table_w, table_h, json.dumps(info))
        del builder
        if bar is not None:
            bar.close()
        replace_dir(tmp, out, owned=_is_pack_dir)
    except BaseException:
        if bar is not None:
            bar.close()
        for s in sources:
            s.close()
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    return TilePack(out)

"""Sharded pack builds: one painting per task on a Dask cluster (a LocalCluster by default,
or any scheduler address) or a plain process pool, and the merge that turns the shards into a
pack without copying tile data (format version 2 keeps one tile file per painting).

A shard is what a worker leaves in `OUT.shards/` for painting i: `tiles-NNNNN.bin` and
`shard-NNNNN.idx` (written by the core's PackBuilder with first_painting = i: the same bytes
a single-process build writes for that painting), then `shard-NNNNN.json` last, recording
what it was built from and the XXH3-64 of both files and of the record itself. The merge
(PackBuilder.assemble) writes index.bin and manifest.json and the directory is renamed to
OUT. Until then no pack exists at OUT; a rerun with resume reuses every shard whose record
matches the job, follows the manifest schema and is unedited, and whose files are regular
and still hash to what it recorded, and builds the rest (shard_records)."""

from __future__ import annotations

import contextlib
import json
import os
import queue
import shutil
import signal
import threading
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from .. import _core
from ..outputs import (MARK, check_output, fsync_dir as _fsync_dir, has_mark, owned_by, replace_dir,
                       write_mark)
from .cluster import run_on_dask
from .images import ImageSource, open_image
from .shard_records import (NotRegularFile, file_hash as _file_hash, read_record, record_digest,
                            record_problem, require_regular_or_missing)

__all__ = ["build_sharded", "build_shard", "feed", "local_cluster", "publish"]


# ----------------------------------------------------------------------------- streaming

def _prefetch(it: Iterator[np.ndarray]) -> Iterator[np.ndarray]:
    """Runs the band reader one band ahead on a helper thread (OpenImageIO releases the GIL
    while decoding), so reading overlaps the C++ reduction and tile cutting. At most two
    bands are alive at once (the one being packed and the one being read): peak memory."""
    q: queue.Queue = queue.Queue()
    slots = threading.Semaphore(2)
    stop = threading.Event()
    done = object()

    def worker():
        try:
            while True:
                while not slots.acquire(timeout=0.1):
                    if stop.is_set():
                        return
                if stop.is_set():
                    return
                band = next(it, done)
                q.put(band)
                if band is done:
                    return
        except BaseException as e:  # handed to the consumer
            q.put(e)

    t = threading.Thread(target=worker, name="gigascroll-band-reader", daemon=True)
    t.start()
    try:
        while True:
            item = q.get()
            if item is done:
                return
            if isinstance(item, BaseException):
                raise item
            yield item
            del item
            slots.release()  # the consumer is done with this band
    finally:
        stop.set()
        t.join()


def feed(builder, source: ImageSource, bar=None) -> None:
    """Streams one image into the builder's open painting."""
    bands = _prefetch(source.bands())
    try:
        for band in bands:
            builder.add_rows(band)
            if bar is not None:
                bar.update(band.shape[0] * band.shape[1] / 1e6)
    finally:
        bands.close()  # joins the reader thread before the image is closed


# Publishing a finished pack (the atomic swap) is the shared outputs.replace_dir.
publish = replace_dir


# ----------------------------------------------------------------------------- one shard

def _shard_paths(directory: Path, index: int) -> tuple[Path, Path, Path]:
    return (directory / f"tiles-{index:05d}.bin", directory / f"shard-{index:05d}.idx",
            directory / f"shard-{index:05d}.json")


def input_identity(image) -> dict:
    """What a shard was built from: a file's path, size and modification time, or an array's
    shape, type and content hash."""
    if isinstance(image, np.ndarray):
        import xxhash
        a = np.ascontiguousarray(image)
        return {"array": list(a.shape), "dtype": a.dtype.str,
                "xxh3": xxhash.xxh3_64_hexdigest(a.view(np.uint8).reshape(-1).data)}
    st = os.stat(image)
    return {"path": os.path.abspath(image), "size": st.st_size, "mtime_ns": st.st_mtime_ns}


def build_shard(directory: str, index: int, image, name: str, opts: dict, job: dict,
                hook: Callable[[int, str], None] | None = None) -> dict:
    """Builds painting `index` of a pack into `directory` (a worker's task) and returns its
    record (also written to shard-NNNNN.json, last)."""
    if hook is not None:
        hook(index, name)
    d = Path(directory)
    tiles, idx, rec_path = _shard_paths(d, index)
    # Built in a private directory and renamed in when complete: a task a lost worker left
    # running (or one the cluster recomputes) never exposes a half-written shard.
    work = d / f".work-{index:05d}-{os.getpid()}-{threading.get_ident()}"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    try:
        source = open_image(image, name, opts["band_rows"], opts["colour"])
        try:
            builder = _core.PackBuilder(work, opts["tile_size"], opts["border"], opts["codec"],
                                        opts["zstd_level"], opts["threads"],
                                        bc1_fit=opts.get("bc1_fit", "range"),
                                        first_painting=index)
            builder.begin_painting(source.name, source.width, source.height, source.source,
                                   source.conversion, 0, 0,
                                   "" if source.colour is None else json.dumps(source.colour))
            feed(builder, source)
            builder.end_painting()
            builder.finish_shard()
            del builder
        finally:
            source.close()
        record = {"job": job, "name": source.name, "width": source.width,
                  "height": source.height, "source": source.source,
                  "conversion": source.conversion, "colour": source.colour,
                  "tiles_xxh3": _file_hash(work / tiles.name),
                  "index_xxh3": _file_hash(work / idx.name)}
        record["record_xxh3"] = record_digest(record)
        with open(work / rec_path.name, "w") as f:
            json.dump(record, f)
            f.flush()
            os.fsync(f.fileno())
        for path in (tiles, idx, rec_path):  # the record last: it marks the shard complete
            os.rename(work / path.name, path)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return record


def _completed_shard(directory: Path, index: int, job: dict) -> dict | None:
    """The record of a shard that was completed for this job and still verifies, else None:
    its record valid by the manifest schema and unedited (shard_records). NotRegularFile
    where a FIFO, a device (a link to /dev/zero) or a directory stands in for one of its
    files: such a shard directory was tampered with; nothing of it is read or removed."""
    tiles, idx, rec_path = _shard_paths(directory, index)
    for path in (tiles, idx, rec_path):
        require_regular_or_missing(path)
    try:
        record = read_record(rec_path)
        if record.get("job") != job or record_problem(record) is not None:
            return None
        if _file_hash(tiles) != record["tiles_xxh3"] or _file_hash(idx) != record["index_xxh3"]:
            return None
    except NotRegularFile:
        raise
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        return None
    return record


# ----------------------------------------------------------------------------- executors

def local_cluster(workers: int):
    """A LocalCluster of `workers` one-thread worker processes for shard builds. Dask's nannies
    set MALLOC_TRIM_THRESHOLD_=65536 for their workers, which makes glibc return every freed
    band buffer to the kernel and fault it back in (much system time); the builder frees and
    reuses buffers of a few MB per band, so its workers keep glibc's default behaviour."""
    import logging
    import dask
    from dask.distributed import LocalCluster
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_":
                          str(1 << 28)}):
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                            dashboard_address=":0", silence_logs=logging.CRITICAL)


def _run_processes(tasks, workers: int, on_done) -> None:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    with ProcessPoolExecutor(max_workers=workers,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(build_shard, *args): i for i, args in tasks}
        try:
            for fut in as_completed(futures):
                on_done(futures[fut], fut.result())
        finally:
            for fut in futures:
                fut.cancel()


def _is_lost_worker(e: BaseException) -> bool:
    from concurrent.futures.process import BrokenProcessPool
    return isinstance(e, BrokenProcessPool) or type(e).__name__ == "KilledWorker"


# ----------------------------------------------------------------------------- the build

def build_sharded(inputs, sources: list[ImageSource], offsets, table: tuple[int, int],
                  info: dict, out: Path, opts: dict, *, workers: int, scheduler: str | None,
                  executor: str, resume: bool, progress: bool,
                  hook: Callable[[int, str], None] | None,
                  owned: Callable[[Path], bool] | None = None,
                  timeout: float | None = None, instances=()) -> None:
    """The sharded build of build_pack (which has opened `sources` for their sizes and names
    and planned the layout): shards in OUT.shards/, then the merge and the rename (over an
    existing pack only where `owned` says it is one). `instances`: (name, source index,
    table_x, table_y) of the paintings that share a stored one's tiles (no shard)."""
    shard_dir = _shard_dir(out, resume)
    n = len(sources)
    jobs = [{"index": i, "name": s.name, "input": input_identity(image), "options": opts}
            for i, (s, image) in enumerate(zip(sources, inputs))]
    records: dict[int, dict] = {}
    if resume:
        for i, job in enumerate(jobs):
            if (rec := _completed_shard(shard_dir, i, job)) is not None:
                records[i] = rec
    reused = len(records)
    todo = [i for i in range(n) if i not in records]
    for i in todo:  # leftovers of an unfinished attempt
        for f in _shard_paths(shard_dir, i):
            f.unlink(missing_ok=True)
    tasks = [(i, (str(shard_dir), i, inputs[i], sources[i].name, opts, jobs[i], hook))
             for i in todo]
    bar = None

    def start_bar() -> None:  # once the workers are there: a failed connection shows none
        nonlocal bar
        if progress and todo and bar is None:
            from tqdm import tqdm
            bar = tqdm(total=n, initial=reused, unit="painting", desc="pack shards")

    def on_done(i: int, record: dict) -> None:
        records[i] = record
        if bar is not None:
            bar.update(1)

    try:
        if tasks:
            workers = max(1, min(workers, len(tasks)))  # no idle worker processes
            if executor == "processes" and scheduler is None:
                start_bar()
                _run_processes(tasks, workers, on_done)
            else:
                run_on_dask(build_shard, tasks, workers, scheduler, on_done, local_cluster,
                            timeout, on_ready=start_bar)
    except BaseException as e:
        if bar is not None:
            bar.close()
        kept = len(records)
        _drop_if_bare(shard_dir)  # nothing built (a scheduler never reached): nothing to resume
        note = (f"{kept} of {n} shards are complete in {shard_dir}; rerun with --resume "
                "(resume=True) to reuse them")
        if _is_lost_worker(e):
            failed = [sources[i].name for i in todo if i not in records]
            raise OSError(f"a worker was lost while building painting(s) "
                          f"{', '.join(failed[:5])}: {e}; {note}") from None
        if isinstance(e, (ValueError, OSError)):
            e.add_note(note)
        raise
    if bar is not None:
        bar.close()

    for i, s in enumerate(sources):  # what the workers saw must be what the layout planned
        r = records[i]
        if (why := record_problem(r)) is not None:  # nothing unchecked goes into the manifest
            raise OSError(f"shard {i} in {shard_dir}: its record cannot go into a manifest: "
                          f"{why}")
        if (r["name"], r["width"], r["height"]) != (s.name, s.width, s.height):
            raise OSError(f"shard {i} holds '{r['name']}' {r['width']} x {r['height']}, "
                          f"expected '{s.name}' {s.width} x {s.height}")
    paintings = [(r["name"], r["width"], r["height"], r["source"], r["conversion"], ox, oy,
                  "" if r["colour"] is None else json.dumps(r["colour"]))
                 for r, (ox, oy) in ((records[i], offsets[i]) for i in range(n))]
    _core.PackBuilder.assemble(shard_dir, opts["tile_size"], opts["border"], opts["codec"],
                               paintings, table[0], table[1], json.dumps(info),
                               instances=list(instances))
    for i in range(n):  # the pack is complete: the shard records go
        _, idx, rec = _shard_paths(shard_dir, i)
        idx.unlink()
        rec.unlink()
    (shard_dir / MARK).unlink()  # the work directory's mark: not part of the pack
    _fsync_dir(shard_dir)
    replace_dir(shard_dir, out, owned=owned)


def _drop_if_bare(shard_dir: Path) -> None:
    """Removes OUT.shards/ when it holds nothing but its own mark (a build that failed before
    any shard was written leaves no work directory behind)."""
    with contextlib.suppress(OSError):
        if [p.name for p in shard_dir.iterdir()] == [MARK] and has_mark(shard_dir, "pack-shards"):
            shutil.rmtree(shard_dir)


def _shard_dir(out: Path, resume: bool) -> Path:
    """OUT.shards/, marked as this output's work directory. An existing one is reused (resume)
    or removed only when its mark names this output; any other is refused."""
    shard_dir = out.parent / f"{out.name}.shards"
    owner = {"output": os.path.join(os.path.realpath(out.parent), out.name)}
    if check_output(shard_dir, force=True, directory=True, owned=owned_by("pack-shards", **owner),
                    what=f"the shard directory of a build of {out}") and not resume:
        shutil.rmtree(shard_dir)
    shard_dir.mkdir(parents=True, exist_ok=True)
    write_mark(shard_dir, "pack-shards", **owner)
    return shard_dir

"""`gigascroll bench cluster`: sharded pack builds of VT-mobile-VR's eight Table 4 paintings (at
reduced size, synthesized as tiled TIFFs) on 1 and 2 workers of a Dask LocalCluster, next to
a plain process pool (the same shard function under concurrent.futures) as the floor to beat,
and a single-process build. Every worker uses one thread, so the worker count is the
parallelism; the scaling ratio is t(1 worker) / t(2 workers). Dask's build time is measured
on a cluster that is already running, its workers having imported gigascroll (start-up
reported on its own); the pool's includes starting its processes and their imports. Every pack is checked to be byte-identical to the
single-process one."""

from __future__ import annotations

import filecmp
import os
import shutil
import statistics
import time
from pathlib import Path

from ..errors import UserError
from ..experiments import write_json


def add_arguments(p) -> None:
    p.add_argument("--scale", type=int, default=16,
                   help="divide the Table 4 sizes by this in each dimension (default 16)")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2],
                   help="worker counts (default 1 2)")
    p.add_argument("--repeat", type=int, default=1, help="runs of each configuration (median)")
    p.add_argument("--codec", default="raw", choices=["raw", "zstd"])
    p.add_argument("--workdir", default="build/bench-cluster",
                   help="synthesized paintings and outputs (default build/bench-cluster)")


def _dir_equal(a: Path, b: Path) -> bool:
    names = sorted(os.listdir(a))
    return names == sorted(os.listdir(b)) and all(
        filecmp.cmp(a / n, b / n, shallow=False) for n in names)


def _warm() -> None:
    import gigascroll.pack.shards  # noqa: F401


def run(args) -> int:
    from ..pack import build_pack, synth_painting
    from ..views.exhibition import TABLE4_PAINTINGS
    try:
        from dask.distributed import Client

        from ..pack.cluster import quiet_dask
        from ..pack.shards import local_cluster
    except ImportError as e:
        raise UserError(f"dask.distributed is needed ({e}): pip install 'gigascroll[cluster]'")
    if args.scale < 1 or args.repeat < 1 or min(args.workers) < 1:
        raise UserError("--scale, --repeat and --workers must be positive")
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    inputs = []
    for spec in TABLE4_PAINTINGS:
        w, h = max(1, spec.width // args.scale), max(1, spec.height // args.scale)
        path = work / f"{spec.name}-{w}x{h}.tif"
        if not path.exists():
            print(f"synthesizing {path.name}")
            synth_painting(path, w, h, seed=len(inputs))
        inputs.append(str(path))
    mpx = sum(s.width // args.scale * (s.height // args.scale) for s in TABLE4_PAINTINGS) / 1e6
    common = {"tile_size": 128, "border": 4, "codec": args.codec, "force": True}

    made: set[Path] = set()  # the packs this run built: the only ones it removes

    def timed(label, out, **kw):
        made.add(out)
        t = time.perf_counter()
        build_pack(inputs, out, threads=1, **common, **kw)
        return time.perf_counter() - t

    results: dict[str, list[float]] = {}
    ref = work / "single.pack"
    clusters, startup = {}, {}
    # distributed logs its own shutdown races (a closed stream) as tracebacks: silenced.
    with quiet_dask():
        try:
            for n in args.workers:  # all started first, so the runs below can interleave
                t = time.perf_counter()
                clusters[n] = local_cluster(n)
                # The workers import the package, as a cluster's would.
                with Client(clusters[n]) as client:
                    client.run(_warm)
                startup[n] = time.perf_counter() - t
            # Configurations interleaved in each repeat: the machine's load drifts.
            for r in range(args.repeat):
                configs = [("single process", ref, {})]
                for n in args.workers:
                    configs.append((f"process pool {n}", work / f"pool-{n}.pack",
                                    {"workers": n, "executor": "processes"}))
                    configs.append((f"dask {n}", work / f"dask-{n}.pack",
                                    {"scheduler": clusters[n].scheduler_address}))
                for label, out, kw in configs:
                    results.setdefault(label, []).append(timed(label, out, **kw))
                    if out != ref:
                        assert _dir_equal(ref, out), f"the {label} pack differs from the single one"
                    print(f"[{r + 1}] {label}: {results[label][-1]:.2f} s", flush=True)
        finally:
            for c in clusters.values():
                c.close()
    print("dask LocalCluster start-up (incl. imports): " +
          ", ".join(f"{n} workers {t:.1f} s" for n, t in startup.items()))

    med = {k: statistics.median(v) for k, v in results.items()}
    print(f"\neight Table 4 paintings / {args.scale} ({mpx:.0f} Mpixel), tile 128, {args.codec}, "
          f"one thread per worker, {os.cpu_count()} cores")
    print(f"{'configuration':<22}{'wall s':>8}{'Mpixel/s':>10}{'scaling':>9}")
    for k, v in med.items():
        kind, _, n = k.rpartition(" ")
        one = med.get(f"{kind} 1") if kind in ("process pool", "dask") else None
        scaling = f"{one / v:9.2f}" if one else " " * 9
        print(f"{k:<22}{v:>8.2f}{mpx / v:>10.1f}{scaling}")
    for n in args.workers:
        if f"dask {n}" in med and f"process pool {n}" in med:
            print(f"dask / pool at {n} workers: speed ratio {med[f'process pool {n}'] / med[f'dask {n}']:.2f}")
    write_json(work / "bench_cluster.json", {"scale": args.scale, "mpixel": mpx,
                                             "codec": args.codec, "runs": results,
                                             "median_seconds": med,
                                             "dask_startup_seconds": startup}, indent=2)
    for p in made:  # not every *.pack of --workdir: a user's packs may live there
        shutil.rmtree(p, ignore_errors=True)
    return 0

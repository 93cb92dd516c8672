"""`gigascroll bench photon`: seed 001's Tables 1-5 on the CPU, the C++ radius-search benchmark
against nanoflann, and run time against error for our estimator and Mitsuba 3's path tracer.

Every time is the median over --repeat runs, measured in this process on the same cores;
speedups are ratios within the same run. Radii are the seed's (0.02-0.2, for its Cornell box
about 2 units wide) times the scene's scale (cornell 1, office 4).
"""

from __future__ import annotations

import json
import math
import statistics
import subprocess
import time
from pathlib import Path

import numpy as np

from ..errors import UserError
from ..experiments import pyplot, save_figure, timed, write_json

# Seed 001's settings and numbers (RTX 2080 Ti, ms), to print next to ours.
SEED_TABLE1 = {  # (photons side, radius): (kd-tree, hash grid)
    (512, 0.02): (7.28, 3.89), (512, 0.05): (118.35, 90.74), (512, 0.1): (426.39, 501.79),
    (256, 0.05): (8.32, 5.23), (256, 0.1): (72.05, 49.29), (256, 0.2): (287.87, 362.10),
    (128, 0.05): (2.57, 1.94), (128, 0.1): (5.69, 3.67), (128, 0.2): (36.29, 22.90),
}
SEED_TABLE2 = {  # (side, radius): (heap, no heap)
    (512, 0.02): (3.89, 2.33), (512, 0.05): (90.74, 4.36), (512, 0.1): (501.79, 11.43),
    (256, 0.05): (5.23, 2.30), (256, 0.1): (49.29, 3.94), (256, 0.2): (362.10, 11.24),
}
SEED_TABLE5 = {(512, 0.05): (15.22, 13.14), (512, 0.1): (25.01, 22.30), (512, 0.15): (33.42, 24.52)}
SCALE = {"cornell": 1.0, "office": 4.0}
IPD = {"cornell": 0.1, "office": 0.064}  # office in metres; the Cornell box is 2 units wide


def add_arguments(parser) -> None:
    parser.add_argument("--scenes", default="cornell,office", help="comma-separated: cornell, office")
    parser.add_argument("--width", type=int, default=256, help="image width and height (default 256)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing (median)")
    parser.add_argument("-k", type=int, default=100, help="heap size of the k-nearest gathers")
    parser.add_argument("--error-size", type=int, default=64, help="image size of the run-time/error study")
    parser.add_argument("--reference-spp", type=int, default=4096, help="Mitsuba reference spp")
    parser.add_argument("--quick", action="store_true", help="small settings, for a smoke test")
    parser.add_argument("--skip", default="", help="comma-separated parts to skip: tables, nanoflann, error")
    parser.add_argument("--out", default="bench/photon", help="directory for results.json and the plot")


def run(args) -> int:
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in SCALE:
            raise UserError(f"unknown scene {s!r} (benchmarked: {', '.join(SCALE)})")
    if args.repeat < 1 or args.width < 8 or args.error_size < 8 or args.reference_spp < 1:
        raise UserError("--repeat must be >= 1, --width and --error-size >= 8, --reference-spp >= 1")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.quick:
        args.width, args.repeat, args.error_size, args.reference_spp = 64, 1, 32, 256
    skip = set(args.skip.split(","))
    results: dict = {"machine": _machine(), "date": time.strftime("%Y-%m-%d"), "width": args.width,
                     "repeat": args.repeat, "k": args.k}
    if "tables" not in skip:
        for name in scenes:
            results[name] = _tables(name, args)
    if "nanoflann" not in skip:
        results["nanoflann"] = _nanoflann(args.quick)
    if "error" not in skip:
        results["error"] = _runtime_vs_error(args, out)
    write_json(out / "results.json", results, indent=1)
    print(f"\nwrote {out / 'results.json'}")
    return 0


def _machine() -> str:
    import os
    import platform

    return f"{os.cpu_count()} cores, {platform.machine()}, {platform.system()}"


def _median_time(fn, repeat: int, key: str):
    """Median over repeat runs of fn() -> stats dict of stats[key] (seconds), in ms; and the
    last stats."""
    times, last = [], None
    for _ in range(repeat):
        last = fn()
        times.append(last[key])
    return 1000 * statistics.median(times), last


def _tables(name: str, args) -> dict:
    from tqdm import tqdm

    from .. import photon as P

    scene, cam = P.builtin_scene(name, resolution=(args.width, args.width))
    sc = SCALE[name]
    sides = (128, 256) if args.quick else (128, 256, 512)
    res: dict = {"triangles": scene.triangle_count, "table1": [], "table2": [], "table3": [], "table4": [],
                 "table5": []}
    configs = [(s, r) for (s, r) in SEED_TABLE1 if s in sides]
    bar = tqdm(total=len(configs) * 2 + len(configs) * 4, desc=f"{name} tables", unit="config")

    def gather_ms(side, r, repeat=args.repeat, **kw):
        def once():
            return P.render(scene, cam, photons=side * side, radius=r * sc, seed=1, return_stats=True, **kw)[1]
        return _median_time(once, repeat, "gather_seconds")

    def pipeline_ms(side, r, **kw):
        def once():
            st = P.render(scene, cam, photons=side * side, radius=r * sc, seed=1, return_stats=True, **kw)[1]
            return {"t": st["trace_seconds"] + st["gather_seconds"]}
        return _median_time(once, args.repeat, "t")

    for side, r in configs:
        # Tables 1 and 2: k-nearest with a heap on each structure, and the heap-free gather. The
        # two-pass pipeline times the gathers alone (pass 2), without ray tracing.
        kd, _ = gather_ms(side, r, grid="kdtree", gather="knn", k=args.k, pipeline="two-pass")
        hg, st = gather_ms(side, r, grid="hash", gather="knn", k=args.k, pipeline="two-pass")
        nh, _ = gather_ms(side, r, grid="hash", gather="radius", pipeline="two-pass")
        kdr, _ = gather_ms(side, r, grid="kdtree", gather="radius", pipeline="two-pass")
        bar.update(2)
        res["table1"].append(dict(side=side, r=r, kdtree_ms=kd, hash_ms=hg, kdtree_radius_ms=kdr,
                                  stored=st["photons_stored"], seed=SEED_TABLE1[(side, r)]))
        res["table2"].append(dict(side=side, r=r, heap_ms=hg, noheap_ms=nh, seed=SEED_TABLE2.get((side, r))))
        # Table 3: fused against two-pass (trace + gather, photon pass excluded).
        fused, _ = pipeline_ms(side, r, pipeline="fused")
        two, _ = pipeline_ms(side, r, pipeline="two-pass")
        bar.update(2)
        res["table3"].append(dict(side=side, r=r, fused_ms=fused, two_pass_ms=two))
        # Table 4: per-pixel against cooperative gather (both two-pass; gather pass only).
        per, _ = gather_ms(side, r, pipeline="two-pass")
        coop, _ = gather_ms(side, r, pipeline="two-pass", cooperative=True)
        bar.update(2)
        res["table4"].append(dict(side=side, r=r, per_pixel_ms=per, cooperative_ms=coop))
    bar.close()
    # Table 5: stereo, separate eyes against reuse (both eyes' render, photon pass excluded).
    eyes = P.StereoCamera(cam, ipd=IPD[name])
    side5 = 256 if args.quick else 512
    for r in (0.05, 0.1, 0.15):
        def stereo(reuse):
            def once():
                _, _, st = P.render_stereo(scene, eyes, reuse=reuse, photons=side5 * side5, radius=r * sc, seed=1)
                return {"t": st["left"]["gather_seconds"] + st["right"]["gather_seconds"],
                        "share": st["reused_share"]}
            return _median_time(once, args.repeat, "t")
        sep, _ = stereo(False)
        reu, st = stereo(True)
        res["table5"].append(dict(side=side5, r=r, separate_ms=sep, reuse_ms=reu, reused_share=st["share"],
                                  seed=SEED_TABLE5.get((side5, r))))
    _print_tables(name, res, args)
    return res


def _fmt_seed(pair) -> str:
    return " / ".join(f"{x:.2f}" for x in pair) if pair else "-"


def _print_tables(name: str, res: dict, args) -> None:
    sc = SCALE[name]
    print(f"\n## {name} ({res['triangles']} triangles, {args.width}x{args.width}, 1 spp, radii x {sc:g})")
    print("\nTable 1: k-nearest gather (heap, k=%d), kd-tree vs hash grid (gather pass, ms); seed: kd / hash"
          % args.k)
    print("| photons | r | stored | kd-tree | hash grid | kd/hash | kd-tree, no heap | seed kd / hash |")
    print("|---|---|---|---|---|---|---|---|")
    for e in res["table1"]:
        print(f"| {e['side']}^2 | {e['r']:g} | {e['stored']} | {e['kdtree_ms']:.1f} | {e['hash_ms']:.1f} | "
              f"{e['kdtree_ms'] / e['hash_ms']:.2f}x | {e['kdtree_radius_ms']:.1f} | {_fmt_seed(e['seed'])} |")
    print("\nTable 2: hash grid, heap (k-nearest) vs no heap (radius gather) (gather pass, ms)")
    print("| photons | r | heap | no heap | speedup | seed heap / no heap |")
    print("|---|---|---|---|---|---|")
    for e in res["table2"]:
        print(f"| {e['side']}^2 | {e['r']:g} | {e['heap_ms']:.1f} | {e['noheap_ms']:.1f} | "
              f"{e['heap_ms'] / e['noheap_ms']:.1f}x | {_fmt_seed(e['seed'])} |")
    print("\nTable 3: fused vs two-pass pipeline (trace + gather, ms)")
    print("| photons | r | fused | two-pass | fused/two-pass |")
    print("|---|---|---|---|---|")
    for e in res["table3"]:
        print(f"| {e['side']}^2 | {e['r']:g} | {e['fused_ms']:.1f} | {e['two_pass_ms']:.1f} | "
              f"{e['fused_ms'] / e['two_pass_ms']:.2f}x |")
    print("\nTable 4: per-pixel vs cooperative gather (two-pass, gather pass, ms)")
    print("| photons | r | per-pixel | cooperative | gain |")
    print("|---|---|---|---|---|")
    for e in res["table4"]:
        print(f"| {e['side']}^2 | {e['r']:g} | {e['per_pixel_ms']:.1f} | {e['cooperative_ms']:.1f} | "
              f"{e['per_pixel_ms'] / e['cooperative_ms']:.2f}x |")
    print("\nTable 5: stereo, separate vs reuse (both eyes, photon pass excluded, ms)")
    print("| photons | r | separate | reuse | speedup | reused share | seed separate / reuse |")
    print("|---|---|---|---|---|---|---|")
    for e in res["table5"]:
        print(f"| {e['side']}^2 | {e['r']:g} | {e['separate_ms']:.1f} | {e['reuse_ms']:.1f} | "
              f"{e['separate_ms'] / e['reuse_ms']:.2f}x | {100 * e['reused_share']:.0f}% | {_fmt_seed(e['seed'])} |")


def _nanoflann(quick: bool) -> dict | None:
    """Runs the C++ Google Benchmark bench_photon (hash grid vs nanoflann vs our kd-tree)."""
    root = Path(__file__).resolve().parents[3]
    exes = sorted(root.glob("build/cp3*/bench_photon"))
    if not exes:
        print("\n(bench_photon not built: skipping the nanoflann comparison)")
        return None
    filt = "side:128" if quick else "."
    r = subprocess.run([str(exes[0]), "--benchmark_format=json", f"--benchmark_filter={filt}"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        print(f"\nbench_photon failed: {r.stderr.strip()[:500]}")
        return None
    data = json.loads(r.stdout)
    rows: dict = {}
    for b in data["benchmarks"]:
        name, *params = b["name"].split("/")
        kv = dict(p.split(":") for p in params if ":" in p)
        if "side" not in kv or "r_index" not in kv:
            continue
        key = (int(kv["side"]), [0.02, 0.05, 0.1, 0.2][int(kv["r_index"])])
        rows.setdefault(key, {})[name.replace("BM_", "")] = b["real_time"]
        rows[key]["found"] = b.get("found/query", 0)
        rows[key]["stored"] = b.get("photons", 0)
    print("\nRadius search, Cornell photons, 128x128 first-hit queries (C++ bench_photon, ms per query set)")
    print("| photons | stored | r | found/query | hash grid | nanoflann | our kd-tree | nanoflann/hash |")
    print("|---|---|---|---|---|---|---|---|")
    for (side, rad), v in sorted(rows.items()):
        if {"HashGrid", "Nanoflann", "KdTree"} <= v.keys():
            print(f"| {side}^2 | {int(v['stored'])} | {rad:g} | {v['found']:.0f} | {v['HashGrid']:.2f} | "
                  f"{v['Nanoflann']:.2f} | {v['KdTree']:.2f} | {v['Nanoflann'] / v['HashGrid']:.2f}x |")
    return {f"{s}/{r}": v for (s, r), v in rows.items()}


def _runtime_vs_error(args, out: Path) -> dict:
    """relMSE to a Mitsuba reference against wall-clock seconds: our estimator over photon
    counts, radii and spp, and Mitsuba's path tracer at increasing spp, on the same cores."""
    from tqdm import tqdm

    from .. import photon as P

    try:
        import mitsuba as mi
    except ImportError:
        print("\n(mitsuba not installed: skipping run time against error)")
        return {}
    mi.set_variant("scalar_rgb")
    size = args.error_size
    d = mi.cornell_box()
    d["sensor"]["film"].update(width=size, height=size, rfilter={"type": "box"})
    d["integrator"] = {"type": "path", "max_depth": -1}
    mscene = mi.load_dict(d)
    seconds, ref = timed(lambda: np.array(mi.render(mscene, spp=args.reference_spp, seed=12345),
                                          dtype=np.float32))
    print(f"\nreference: Mitsuba path tracer, {size}x{size}, {args.reference_spp} spp, "
          f"{seconds:.1f} s")
    spps = [1, 4, 16, 64, 256] if args.quick else [1, 4, 16, 64, 256, 1024]
    mitsuba = []
    for spp in tqdm(spps, desc="mitsuba", unit="run"):
        seconds, img = timed(lambda: np.array(mi.render(mscene, spp=spp, seed=spp), dtype=np.float32))
        mitsuba.append(dict(spp=spp, seconds=seconds, relmse=P.relmse(img, ref)))
    scene, cam = P.builtin_scene("cornell", resolution=(size, size))
    P.render(scene, cam, photons=1000, radius=0.05)  # warm-up
    ours = []
    photon_counts = [1 << 14, 1 << 16, 1 << 18] if args.quick else [1 << 14, 1 << 16, 1 << 18, 1 << 20, 1 << 22]
    configs = [(n, r, spp) for n in photon_counts for r in (0.01, 0.02, 0.04) for spp in (4, 16, 64)]
    for n, r, spp in tqdm(configs, desc="photon mapping", unit="run"):
        seconds, img = timed(lambda: P.render(scene, cam, photons=n, radius=r, spp=spp, seed=7))
        ours.append(dict(photons=n, radius=r, spp=spp, seconds=seconds, relmse=P.relmse(img, ref)))
    front = _pareto(ours)
    print("\nRun time against error, Cornell box (relMSE to the reference)")
    print("| Mitsuba spp | s | relMSE | our fastest config at or below that relMSE | s | speedup |")
    print("|---|---|---|---|---|---|")
    comparisons = []
    for m in mitsuba:
        best = min((o for o in ours if o["relmse"] <= m["relmse"]), key=lambda o: o["seconds"], default=None)
        if best is None:
            print(f"| {m['spp']} | {m['seconds']:.2f} | {m['relmse']:.5f} | none (below our bias floor) | - | - |")
        else:
            cfg = f"2^{int(math.log2(best['photons']))} photons, r {best['radius']:g}, {best['spp']} spp"
            print(f"| {m['spp']} | {m['seconds']:.2f} | {m['relmse']:.5f} | {cfg} ({best['relmse']:.5f}) | "
                  f"{best['seconds']:.2f} | {m['seconds'] / best['seconds']:.1f}x |")
        comparisons.append(dict(mitsuba=m, ours=best))
    print("\nOur Pareto front:")
    for o in front:
        print(f"  2^{int(math.log2(o['photons']))} photons, r {o['radius']:g}, {o['spp']} spp: "
              f"{o['seconds']:.2f} s, relMSE {o['relmse']:.5f}")
    _plot(mitsuba, ours, front, out / "runtime_vs_error.png", size, args.reference_spp)
    return dict(size=size, reference_spp=args.reference_spp, mitsuba=mitsuba, ours=ours, comparisons=comparisons)


def _pareto(points: list[dict]) -> list[dict]:
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: p["seconds"]):
        if p["relmse"] < best:
            front.append(p)
            best = p["relmse"]
    return front


def _plot(mitsuba, ours, front, path: Path, size: int, ref_spp: int) -> None:
    fig, ax = pyplot().subplots(figsize=(7, 5))
    ax.loglog([m["seconds"] for m in mitsuba], [m["relmse"] for m in mitsuba], "o-", color="tab:blue",
              label="Mitsuba 3 path tracer (spp 1..1024)")
    for m in mitsuba:
        ax.annotate(f"{m['spp']}", (m["seconds"], m["relmse"]), fontsize=7, textcoords="offset points",
                    xytext=(3, 3))
    ax.scatter([o["seconds"] for o in ours], [o["relmse"] for o in ours], s=10, color="tab:orange", alpha=0.4,
               label="photon mapping (photons x radius x spp)")
    ax.loglog([o["seconds"] for o in front], [o["relmse"] for o in front], "s-", color="tab:red",
              label="photon mapping, Pareto front")
    ax.set_xlabel("wall-clock seconds (2 cores)")
    ax.set_ylabel(f"relMSE to Mitsuba {ref_spp} spp")
    ax.set_title(f"Cornell box {size}x{size}: run time against error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    print(f"wrote {path}")

"""`gigascroll bench photon`: VR-photon-mapping's Tables 1-5 on the CPU, the C++ radius-search
benchmark against nanoflann, and run time against error (one-shot and progressive photon mapping
against Mitsuba 3's path and particle tracers) for the Cornell box and the three test rooms.

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
from ..experiments import pyplot, save_figure, write_json

# VR-photon-mapping's settings and numbers (RTX 2080 Ti, ms), to print next to ours.
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
    parser.add_argument("--reference-spp", type=int, default=4096,
                        help="Mitsuba reference spp (two halves of different seeds, whose difference gives the "
                             "reference's own noise)")
    parser.add_argument("--error-scenes", default=",".join(ERROR_SCENES),
                        help="comma-separated scenes of the run-time/error study (default: all four)")
    parser.add_argument("--quick", action="store_true", help="small settings, for a smoke test")
    parser.add_argument("--skip", default="", help="comma-separated parts to skip: tables, nanoflann, error")
    parser.add_argument("--part", choices=("all", "tables", "nanoflann", "error"), default="all",
                        help="run only this part (error: run time against error for the Cornell box and "
                             "the three test rooms, one plot per scene)")
    parser.add_argument("--out", default="bench/photon", help="directory for results.json and the plot")


def run(args) -> int:
    scenes = [s for s in args.scenes.split(",") if s]
    for s in scenes:
        if s not in SCALE:
            raise UserError(f"unknown scene {s!r} (benchmarked: {', '.join(SCALE)})")
    bad = set(args.error_scenes.split(",")) - set(ERROR_SCENES)
    if bad:
        raise UserError(f"unknown error-study scene(s) {', '.join(sorted(bad))} (known: {', '.join(ERROR_SCENES)})")
    if args.repeat < 1 or args.width < 8 or args.error_size < 8 or args.reference_spp < 1:
        raise UserError("--repeat must be >= 1, --width and --error-size >= 8, --reference-spp >= 1")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.quick:
        args.width, args.repeat, args.error_size, args.reference_spp = 64, 1, 32, 256
    skip = set(args.skip.split(","))
    if args.part != "all":
        skip |= {"tables", "nanoflann", "error"} - {args.part}
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

    # The seed's tables gather over the sphere (disc=False), as VR-photon-mapping does.
    def gather_ms(side, r, repeat=args.repeat, **kw):
        def once():
            return P.render(scene, cam, photons=side * side, radius=r * sc, seed=1, return_stats=True,
                            disc=False, **kw)[1]
        return _median_time(once, repeat, "gather_seconds")

    def pipeline_ms(side, r, **kw):
        def once():
            st = P.render(scene, cam, photons=side * side, radius=r * sc, seed=1, return_stats=True,
                          disc=False, **kw)[1]
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
        fused, _ = pipeline_ms(side, r, grid="hash", pipeline="fused")
        two, _ = pipeline_ms(side, r, grid="hash", pipeline="two-pass")
        bar.update(2)
        res["table3"].append(dict(side=side, r=r, fused_ms=fused, two_pass_ms=two))
        # Table 4: per-pixel against cooperative gather (both two-pass; gather pass only).
        per, _ = gather_ms(side, r, grid="hash", pipeline="two-pass")
        coop, _ = gather_ms(side, r, grid="hash", pipeline="two-pass", cooperative=True)
        bar.update(2)
        res["table4"].append(dict(side=side, r=r, per_pixel_ms=per, cooperative_ms=coop))
    bar.close()
    # Table 5: stereo, separate eyes against reuse (both eyes' render, photon pass excluded).
    eyes = P.StereoCamera(cam, ipd=IPD[name])
    side5 = 256 if args.quick else 512
    for r in (0.05, 0.1, 0.15):
        def stereo(reuse):
            def once():
                _, _, st = P.render_stereo(scene, eyes, reuse=reuse, photons=side5 * side5, radius=r * sc, seed=1,
                                           grid="hash")
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


BENCH_PHOTON_SCENES = ("cornell", "office")  # bench_photon's scene index
BENCH_PHOTON_RADII = (0.02, 0.05, 0.1, 0.2)  # times the scene's scale
BENCH_PHOTON_ARGS = ("--benchmark_filter=-BM_AdaptiveCells", "--benchmark_repetitions=3",
                     "--benchmark_enable_random_interleaving=true", "--benchmark_report_aggregates_only=true")


def _nanoflann(quick: bool) -> dict | None:
    """Runs the C++ Google Benchmark bench_photon: our adaptive grid, VR-photon-mapping's hash grid,
    nanoflann and our kd-tree on the same photons and queries, repeated 3 times with the runs
    interleaved at random (the machine is shared); reports the median CPU time per query set."""
    root = Path(__file__).resolve().parents[3]
    exes = sorted(root.glob("build/cp3*/bench_photon"))
    if not exes:
        print("\n(bench_photon not built: skipping the nanoflann comparison)")
        return None
    args = list(BENCH_PHOTON_ARGS)
    if quick:
        args = ["--benchmark_filter=^BM_(Adaptive|HashGrid|Nanoflann|KdTree)/scene:0/side:128/"]
    cmd = [str(exes[0]), "--benchmark_format=json", *args]
    print("\n$ " + " ".join(["bench_photon", *cmd[1:]]))
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(f"\nbench_photon failed: {r.stderr.strip()[:500]}")
        return None
    return _print_bench_photon(json.loads(r.stdout))


def _print_bench_photon(data: dict) -> dict:
    rows: dict = {}
    for b in data["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        name, *params = b.get("run_name", b["name"]).split("/")
        kv = dict(p.split(":") for p in params if ":" in p)
        if not {"scene", "side", "r_index"} <= kv.keys() or "quarter_cells" in kv:
            continue
        scene = BENCH_PHOTON_SCENES[int(kv["scene"])]
        key = (scene, int(kv["side"]), BENCH_PHOTON_RADII[int(kv["r_index"])])
        row = rows.setdefault(key, {})
        row[name.replace("BM_", "")] = b["cpu_time"]
        if name == "BM_Adaptive":
            row["found"] = b.get("found/query", 0)
            row["stored"] = b.get("photons", 0)
            row["cells_per_radius"] = b.get("cells_per_radius", 0)
    print("\nRadius search, 128x128 first-hit queries (C++ bench_photon, median CPU ms per query set; "
          "radii x scene scale: cornell 1, office 4)")
    print("| scene | photons | stored | r | found/query | cells/r | adaptive (ours) | seed hash grid | nanoflann | "
          "our kd-tree | nanoflann/adaptive | kd-tree/adaptive | seed grid/adaptive |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (scene, side, rad), v in sorted(rows.items(), key=lambda kv: (BENCH_PHOTON_SCENES.index(kv[0][0]),) + kv[0][1:]):
        if {"Adaptive", "HashGrid", "Nanoflann", "KdTree"} <= v.keys():
            a = v["Adaptive"]
            print(f"| {scene} | {side}^2 | {int(v['stored'])} | {rad:g} | {v['found']:.0f} | {v['cells_per_radius']:g} | "
                  f"{a:.2f} | {v['HashGrid']:.2f} | {v['Nanoflann']:.2f} | {v['KdTree']:.2f} | "
                  f"{v['Nanoflann'] / a:.2f}x | {v['KdTree'] / a:.2f}x | {v['HashGrid'] / a:.2f}x |")
    return {f"{sc}/{s}/{r}": v for (sc, s, r), v in rows.items()}


ERROR_SCENES = ("cornell", "room_lit", "room_indirect", "room_partition")
TARGET_RELMSE = 1e-4  # issue 12 §5: no error floor above it within the time Mitsuba needs to reach it


def _mitsuba_dict(name: str, size: int, integrator: str) -> dict:
    """The scene for mitsuba.load_dict: mi.cornell_box() with our pixel filter, or the room's
    own export (RoomScene.to_mitsuba_dict)."""
    import mitsuba as mi

    from .. import photon as P

    if name == "cornell":
        d = mi.cornell_box()
        d["sensor"]["film"].update(width=size, height=size, rfilter={"type": "box"})
        d["integrator"] = {"type": integrator, "max_depth": -1}
        return d
    return P.room_scene(name).to_mitsuba_dict(resolution=(size, size), integrator={"type": integrator,
                                                                                  "max_depth": -1})


def _runtime_vs_error(args, out: Path) -> dict:
    """relMSE to a Mitsuba reference against wall-clock seconds, per scene: the one-shot photon
    mapper over photon counts, radii and spp; the progressive one (one render, an image after
    each power-of-two pass count), sphere and surface-disc gathers; Mitsuba's path tracer at
    increasing spp (and its particle tracer in the indirectly lit room), all on the same cores."""
    try:
        import mitsuba as mi
    except ImportError:
        print("\n(mitsuba not installed: skipping run time against error)")
        return {}
    mi.set_variant("scalar_rgb")
    return {name: _error_study(name, args, out) for name in ERROR_SCENES if name in args.error_scenes.split(",")}


def _reference_half(name: str, size: int, spp: int, integrator: str, seed: int) -> np.ndarray:
    """One Mitsuba render, cached under build/photon-reference (rendered once)."""
    import mitsuba as mi

    path = Path("build") / "photon-reference" / f"bench_{name}{size}_{integrator}{spp}spp_seed{seed}.npy"
    if path.exists():
        return np.load(path)
    t0 = time.perf_counter()
    ref = np.array(mi.render(mi.load_dict(_mitsuba_dict(name, size, integrator)), spp=spp, seed=seed),
                   dtype=np.float32)
    print(f"reference {name}: Mitsuba {integrator}, {size}x{size}, {spp} spp, seed {seed}, "
          f"{time.perf_counter() - t0:.1f} s")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npy")
    np.save(tmp, ref)
    tmp.replace(path)
    return ref


def _reference(name: str, size: int, spp: int, integrator: str) -> tuple[np.ndarray, float]:
    """The scene's Mitsuba reference of spp samples per pixel as the mean of two independent
    halves (seeds 12345 and 54321), and its own noise: the expected relMSE of the mean against
    the truth, relMSE(a, b) / 4 (a - b has twice a half's variance, the mean half of it)."""
    half = max(spp // 2, 1)
    a = _reference_half(name, size, half, integrator, 12345)
    b = _reference_half(name, size, half, integrator, 54321)
    ref = 0.5 * (a + b)
    from .. import photon as P

    return ref, P.relmse(a, b) / 4


def _error_study(name: str, args, out: Path) -> dict:
    import mitsuba as mi
    from tqdm import tqdm

    from .. import photon as P

    size = args.error_size
    # The particle tracer converges ~3x faster than the path tracer in the indirectly lit room.
    ref_integrator = "ptracer" if name == "room_indirect" else "path"
    ref, ref_noise = _reference(name, size, args.reference_spp, ref_integrator)
    print(f"{name}: reference {ref_integrator} {args.reference_spp} spp, its noise (relMSE) {ref_noise:.2e}")
    spps = [1, 4, 16, 64, 256] if args.quick else [1, 4, 16, 64, 256, 1024]
    curves: dict[str, list[dict]] = {}
    for integrator in ("path", "ptracer") if name == "room_indirect" else ("path",):
        mscene = mi.load_dict(_mitsuba_dict(name, size, integrator))
        pts = []
        ladder = list(spps)
        bar = tqdm(desc=f"{name}: mitsuba {integrator}", unit="run")
        while ladder:
            spp = ladder.pop(0)
            t0 = time.perf_counter()
            img = np.array(mi.render(mscene, spp=spp, seed=spp), dtype=np.float32)
            pts.append(dict(spp=spp, seconds=time.perf_counter() - t0, relmse=P.relmse(img, ref)))
            bar.update()
            # The reference's integrator (the faster one) doubles its spp beyond the ladder until
            # it reaches TARGET_RELMSE (at most a quarter of the reference's spp).
            if (not ladder and not args.quick and integrator == ref_integrator and pts[-1]["relmse"] > TARGET_RELMSE
                    and 2 * spp <= args.reference_spp // 4):
                ladder.append(2 * spp)
        bar.close()
        curves[f"mitsuba {integrator}"] = pts
    scene, cam = P.builtin_scene(name, resolution=(size, size))
    r0 = P.default_radius(scene)
    P.render(scene, cam, photons=1000, radius=r0)  # warm-up
    one_shot = []
    photon_counts = [1 << 14, 1 << 16, 1 << 18] if args.quick else [1 << 14, 1 << 16, 1 << 18, 1 << 20]
    # One-shot with the sphere and with the surface disc (the default), configurations interleaved.
    configs = [(n, r, spp, disc) for n in photon_counts for r in (0.5 * r0, r0) for spp in (4, 16, 64)
               for disc in (False, True)]
    for n, r, spp, disc in tqdm(configs, desc=f"{name}: one-shot", unit="run"):
        t0 = time.perf_counter()
        img = P.render(scene, cam, photons=n, radius=r, spp=spp, seed=7, disc=disc)
        one_shot.append(dict(photons=n, radius=r, spp=spp, disc=disc, seconds=time.perf_counter() - t0,
                             relmse=P.relmse(img, ref)))
    curves["one-shot (Pareto front)"] = _pareto([p for p in one_shot if not p["disc"]])
    curves["one-shot disc (Pareto front)"] = _pareto([p for p in one_shot if p["disc"]])
    # Progressive: 2 photons per pixel and pass from 8x the default radius with alpha 0.8 (a
    # sweep at 32x32 in the lit and indirect rooms found it ahead of 4 per pixel from 4x with
    # alpha 2/3, of 1 and of 8 per pixel, and of 16x), for 1.2x as long as Mitsuba needs to
    # reach TARGET_RELMSE (or its longest run); with the sphere and with a final gather for a
    # quarter of that. The curve is the image after pass counts 2^(i/4). The first 64 passes
    # clip the disc coarsely (render's default coarse_passes): the same error per pass, cheaper.
    mitsuba_runs = [p for pts in curves.values() for p in pts]
    reached = [p["seconds"] for p in mitsuba_runs if p["relmse"] <= TARGET_RELMSE]
    budget = 1.2 * (min(reached) if reached else max(p["seconds"] for p in mitsuba_runs))
    shots = sorted({round(2 ** (i / 4)) for i in range(81)})
    # The sphere keeps the earlier settings (4 photons per pixel and pass, 4x the radius, alpha
    # 2/3): from 8x it gathers a wall's photons for the floor.
    default = dict(photons=2 * size * size, radius=8 * r0, alpha=0.8)
    sphere = dict(photons=4 * size * size, radius=4 * r0, alpha=2 / 3, disc=False)
    for label, kw, share in (("progressive disc", default, 1.0), ("progressive sphere", sphere, 0.25),
                             ("progressive disc + final gather", dict(default, final_gather=True), 0.25)):
        _, st = P.render(scene, cam, progressive=True, passes=1 << 20, time_budget=share * budget, snapshots=shots,
                         seed=7, return_stats=True, **kw)
        curves[label] = [dict(passes=k, seconds=sec, relmse=P.relmse(im, ref)) for k, sec, im in st["snapshots"]]
    _print_error_table(name, curves)
    _print_times_to_targets(name, curves)
    _plot(name, curves, out / f"runtime_vs_error_{name}.png", size, args.reference_spp, ref_integrator)
    return dict(size=size, reference=f"{ref_integrator} {args.reference_spp} spp", reference_noise=ref_noise,
                one_shot=one_shot, curves=curves)


def _time_to(curve: list[dict], target: float) -> float | None:
    """Seconds the curve needs to reach relMSE <= target (its fastest such point)."""
    return min((p["seconds"] for p in curve if p["relmse"] <= target), default=None)


def _interpolated_time_to(curve: list[dict], target: float) -> float | None:
    """Seconds at which the curve first crosses relMSE = target, log-log interpolated between
    its neighbouring points (None if it never gets there)."""
    pts = sorted(curve, key=lambda p: p["seconds"])
    for i, p in enumerate(pts):
        if p["relmse"] <= target:
            if i == 0:
                return p["seconds"]
            q = pts[i - 1]
            if q["relmse"] <= p["relmse"] or q["seconds"] <= 0:
                return p["seconds"]
            f = math.log(q["relmse"] / target) / math.log(q["relmse"] / p["relmse"])
            return math.exp(math.log(q["seconds"]) + f * math.log(p["seconds"] / q["seconds"]))
    return None


def _print_times_to_targets(name: str, curves: dict) -> None:
    targets = (3e-3, 2e-3, 1.5e-3, 1e-3, 7e-4, 5e-4, 3e-4, 2e-4, 1e-4)
    print(f"\n{name}: seconds to reach relMSE (log-log interpolated; speedup = the fastest Mitsuba curve's / ours)")
    print("| curve | " + " | ".join(f"{t:g}" for t in targets) + " |")
    print("|---|" + "---|" * len(targets))
    best = {t: min((x for k, c in curves.items() if k.startswith("mitsuba")
                    for x in [_interpolated_time_to(c, t)] if x is not None), default=None) for t in targets}
    for key, c in curves.items():
        cells = []
        for t in targets:
            x = _interpolated_time_to(c, t)
            if x is None:
                cells.append("-")
            elif key.startswith("mitsuba") or best[t] is None:
                cells.append(f"{x:.2f}")
            else:
                cells.append(f"{x:.2f} ({best[t] / x:.1f}x)")
        print(f"| {key} | " + " | ".join(cells) + " |")


def _print_error_table(name: str, curves: dict) -> None:
    ours = [k for k in curves if not k.startswith("mitsuba")]
    print(f"\nRun time against error, {name}: seconds to reach each Mitsuba point's relMSE")
    print("| Mitsuba | spp | s | relMSE | " + " | ".join(ours) + " |")
    print("|---|---|---|---|" + "---|" * len(ours))
    for key in (k for k in curves if k.startswith("mitsuba")):
        for m in curves[key]:
            cells = []
            for o in ours:
                t = _time_to(curves[o], m["relmse"])
                cells.append("-" if t is None else f"{t:.2f} ({m['seconds'] / t:.1f}x)")
            print(f"| {key[8:]} | {m['spp']} | {m['seconds']:.2f} | {m['relmse']:.5f} | " + " | ".join(cells) + " |")
    for o in ours:
        print(f"  {o}: lowest relMSE {min(p['relmse'] for p in curves[o]):.5f}")


def _pareto(points: list[dict]) -> list[dict]:
    front, best = [], math.inf
    for p in sorted(points, key=lambda p: p["seconds"]):
        if p["relmse"] < best:
            front.append(p)
            best = p["relmse"]
    return front


def _plot(name: str, curves: dict, path: Path, size: int, ref_spp: int, ref_integrator: str) -> None:
    fig, ax = pyplot().subplots(figsize=(7, 5))
    for key, pts in curves.items():
        ax.loglog([p["seconds"] for p in pts], [p["relmse"] for p in pts], "o-" if key.startswith("mitsuba") else "s-",
                  label=key, markersize=4)
    ax.set_xlabel("wall-clock seconds (same cores)")
    ax.set_ylabel(f"relMSE to Mitsuba {ref_integrator} {ref_spp} spp")
    ax.set_title(f"{name} {size}x{size}: run time against error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    print(f"wrote {path}")

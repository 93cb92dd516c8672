"""The photon pass and the hall's fine end, timed on their own (bench/RESULTS.md, the gallery
section's lighting figures): median wall-clock seconds of Gallery.light() at 2^16, 2^18 and 2^20
photons in both rooms (its photon_seconds and the rest, the map), and the end-to-end time (light
+ bake + still, as `gigascroll bench gallery` re-times its targets) of the hall's front
configurations at 2^18-2^20 photons from bench/gallery/results.json, with their relMSE against
the cached 4096-spp Mitsuba reference (computed once if it is not in --reference-cache).

Run from the repository root with the project's Python:
    .venv/bin/python bench/gallery/photon_pass.py [--repeats 3] [--out build/photon-pass.json]
Run it on two builds (before and after) alternately, then
    .venv/bin/python bench/gallery/photon_pass.py --compare before1.json,before2.json:after1.json,after2.json
prints the before/after table: the figures are medians of a shared machine's timings
and only their ratio within one period of load means anything. CPU seconds (the process's,
all threads) are less sensitive to the load than wall-clock ones."""
import argparse
import json
import math
import statistics
import tempfile
import time
from pathlib import Path

import mitsuba as mi

mi.set_variant("scalar_rgb")

from gigascroll import TilePack, VirtualTexture  # noqa: E402
from gigascroll.benchmarks.gallery import _still, build_bench_pack, cached_reference  # noqa: E402
from gigascroll.gallery import Gallery, builtin_room  # noqa: E402
from gigascroll.photon import relmse  # noqa: E402

W, H, SS, FOV = 96, 54, 3, 60.0


def setup(pack, room):
    gal = Gallery.from_room(builtin_room(room, pack), pack)
    vt = VirtualTexture(pack, (48, 48))
    gal.stream(gal.camera((W * SS, H * SS), fov=FOV), vt)
    return gal, vt


def front_configs(results: Path):
    """The hall's front configurations at 2^18-2^20 photons that the targets chose."""
    hall = json.loads(results.read_text())["rooms"]["hall"]
    seen, out = set(), []
    for t in hall["targets"]:
        c = t["ours"]
        if c is None or c["photons_log2"] < 18:
            continue
        key = tuple(c[k] for k in ("photons_log2", "light_radius", "disc", "diagonal_over", "bake_samples",
                                   "gather_stride", "coarse_disc", "supersample"))
        if key not in seen:
            seen.add(key)
            out.append(c)
    return out


def compare(before: list[Path], after: list[Path]) -> None:
    """A markdown table of before / after: each row's best median over the runs given (runs
    alternated between the builds, so a busy minute falls on one run, not on one build)."""
    def best(paths):
        runs = [json.loads(p.read_text()) for p in paths]
        light = {k: min(r["light"][k]["seconds"] for r in runs) for k in runs[0]["light"]}
        photon = {k: min(r["light"][k]["photon_seconds"] for r in runs) for k in runs[0]["light"]}
        lcpu = {k: min(r["light"][k]["cpu_seconds"] for r in runs) for k in runs[0]["light"]}
        front = {row["config"]: (min(r["front"][i]["seconds"] for r in runs),
                                 min(r["front"][i]["cpu_seconds"] for r in runs), row["relmse"])
                 for i, row in enumerate(runs[0]["front"])}
        return light, photon, lcpu, front
    (lb, pb, cb, fb), (la, pa, ca, fa) = best(before), best(after)
    print("| light() | before: wall (photon pass), CPU | after: wall (photon pass), CPU | speedup wall (photon pass), CPU |")
    print("|---|---|---|---|")
    for k in lb:
        print(f"| {k} | {lb[k]:.3f} s ({pb[k]:.3f}), {cb[k]:.3f} | {la[k]:.3f} s ({pa[k]:.3f}), {ca[k]:.3f} | "
              f"{lb[k] / la[k]:.2f}x ({pb[k] / pa[k]:.2f}x), {cb[k] / ca[k]:.2f}x |")
    print()
    print("| hall front configuration | before: wall, CPU s, relMSE | after: wall, CPU s, relMSE | speedup wall, CPU |")
    print("|---|---|---|---|")
    for k, (t, c, e) in fb.items():
        t2, c2, e2 = fa[k]
        print(f"| {k} | {t:.3f}, {c:.3f}, {e:.4e} | {t2:.3f}, {c2:.3f}, {e2:.4e} | {t / t2:.2f}x, {c / c2:.2f}x |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--pack", default="build/photon-pass/gallery.pack")
    ap.add_argument("--reference-cache", default="build/gallery-reference")
    ap.add_argument("--results", default="bench/gallery/results.json")
    ap.add_argument("--out", default="build/photon-pass.json")
    ap.add_argument("--skip-light", action="store_true")
    ap.add_argument("--compare", metavar="BEFORE,...:AFTER,...",
                    help="print the before / after table of earlier runs' JSON files instead")
    a = ap.parse_args()
    if a.compare:
        before, after = a.compare.split(":")
        compare([Path(p) for p in before.split(",")], [Path(p) for p in after.split(",")])
        return
    pack_path = Path(a.pack)
    if pack_path.exists():
        pack = TilePack(pack_path)
    else:
        pack_path.parent.mkdir(parents=True, exist_ok=True)
        pack = build_bench_pack(pack_path.parent)
    out = {"light": {}, "front": []}
    for room in ("scroll", "hall"):
        gal, vt = setup(pack, room)
        gal.light(vt, photons=1 << 12)  # warm-up: the albedo image, the threads
        if a.skip_light:
            continue
        for p in (16, 18, 20):
            total, photon, cpu = [], [], []
            for _ in range(a.repeats):
                c0, t0 = time.process_time(), time.perf_counter()
                st = gal.light(vt, photons=1 << p)
                total.append(time.perf_counter() - t0)
                cpu.append(time.process_time() - c0)
                photon.append(st["photon_seconds"])
            row = {"seconds": statistics.median(total), "photon_seconds": statistics.median(photon),
                   "cpu_seconds": statistics.median(cpu),
                   "map_seconds": statistics.median(t - q for t, q in zip(total, photon)),
                   "stored": st["photons_stored"]}
            out["light"][f"{room} 2^{p}"] = row
            print(f"light {room} 2^{p}: {row['seconds']:.4f} s (photons {row['photon_seconds']:.4f}, "
                  f"map {row['map_seconds']:.4f}; CPU {row['cpu_seconds']:.4f} s), {row['stored']} stored", flush=True)
    gal, vt = setup(pack, "hall")
    diag = math.dist(*gal.bounds)
    ref, _ = cached_reference(mi, gal, gal.camera((W, H), fov=FOV), 4096, Path(a.reference_cache))
    for c in front_configs(Path(a.results)):
        times, parts, errors, cpu = [], [], [], []
        for _ in range(a.repeats):
            c0, t0 = time.process_time(), time.perf_counter()
            st = gal.light(vt, photons=1 << c["photons_log2"], radius=c["light_radius"], disc=c["disc"])
            t1 = time.perf_counter()
            gal.bake(spacing=diag / c["diagonal_over"], light_samples=c["bake_samples"],
                     gather_stride=c["gather_stride"], coarse_disc=c["coarse_disc"])
            t2 = time.perf_counter()
            img, still = _still(gal, vt, "baked", W, H, c["supersample"], FOV)
            times.append(t2 - t0 + still)
            cpu.append(time.process_time() - c0)
            parts.append((st["photon_seconds"], t1 - t0 - st["photon_seconds"], t2 - t1, still))
            errors.append(relmse(img, ref))
        med = [statistics.median(p[i] for p in parts) for i in range(4)]
        name = (f"2^{c['photons_log2']}, disc r x {c['disc_radius_factor']}{' coarse' if c['coarse_disc'] else ''}, "
                f"diag/{c['diagonal_over']}, {c['bake_samples']} samples, gathers / {c['gather_stride'] ** 2}, "
                f"{c['supersample']}x{c['supersample']}")
        row = {"config": name, "seconds": statistics.median(times), "cpu_seconds": statistics.median(cpu),
               "photon_bake_map_still": med,
               "relmse": errors[0], "relmse_all_equal": len(set(errors)) == 1, "relmse_grid": c["relmse"]}
        out["front"].append(row)
        print(f"{name}: {row['seconds']:.3f} s (photons {med[0]:.3f}, map {med[1]:.3f}, bake {med[2]:.3f}, "
              f"still {med[3]:.4f}; CPU {row['cpu_seconds']:.3f} s); relMSE {errors[0]:.4e} (grid {c['relmse']:.4e})",
              flush=True)
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

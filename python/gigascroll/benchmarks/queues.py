"""`gigascroll bench queues`: runs the C++ queue microbenchmarks (bench/cpp/bench_queues.cpp)
and summarises them: throughput in items/s and round-trip latency of our SPSC and MPSC queues
against boost::lockfree, moodycamel and the mutex queue, all from one run, with each of ours
as a ratio to the best peer of its kind."""

from __future__ import annotations

import glob
import json
import re
import subprocess
from pathlib import Path

from ..errors import UserError
from ..experiments import pyplot, save_figure, write_json

PEERS = {  # kind -> (ours, peers)
    "spsc": ("OurSpsc", ["BoostSpsc", "RWQueue", "OurMpsc", "BoostQueue", "CQueue", "Locked"]),
    "mpsc": ("OurMpsc", ["BoostQueue", "CQueue", "Locked"]),
}


def add_arguments(p) -> None:
    p.add_argument("--binary", default=None,
                   help="bench_queues executable (default: the one in build/cp3*/)")
    p.add_argument("--filter", default=".", help="Google Benchmark filter regex")
    p.add_argument("--out", default="build/bench/queues", help="JSON and PNG output directory")


def _find_binary(explicit: str | None) -> Path:
    if explicit:
        path = Path(explicit)
    else:
        found = sorted(glob.glob("build/cp3*/bench_queues"))
        if not found:
            raise UserError("bench_queues not found under build/cp3*/ (run `make build`, or pass --binary)")
        path = Path(found[0])
    if not path.is_file():
        raise UserError(f"{path}: no such benchmark executable")
    return path


def parse(report: dict) -> list[dict]:
    """Rows (bench, queue, producers, median items/s or ns) from Google Benchmark JSON."""
    rows = []
    for b in report["benchmarks"]:
        if b.get("aggregate_name", "median") != "median":
            continue
        m = re.match(r"BM_(\w+)<(\w+)>(?:/(\d+))?", b["name"])
        if not m:
            continue
        kind, queue, producers = m.group(1), m.group(2), int(m.group(3) or 1)
        rows.append({"bench": kind, "queue": queue, "producers": producers,
                     "items_per_s": b.get("items_per_second"),
                     "ns": b["real_time"] * {"ns": 1, "us": 1e3, "ms": 1e6, "s": 1e9}[b["time_unit"]]})
    return rows


def summarise(rows: list[dict]) -> list[str]:
    lines = []
    for producers, kind in ((1, "spsc"), (2, "mpsc")):
        ours, peers = PEERS[kind]
        tp = {r["queue"]: r["items_per_s"] for r in rows
              if r["bench"] == "Throughput" and r["producers"] == producers}
        batch = {r["queue"]: r["items_per_s"] for r in rows
                 if r["bench"] == "ThroughputBatch" and r["producers"] == producers}
        if ours not in tp:
            continue
        best = max((q for q in peers if q in tp and q != ours), key=tp.get, default=None)
        lines.append(f"{kind.upper()} throughput, {producers} producer(s):")
        for q, v in sorted(tp.items(), key=lambda kv: -kv[1]):
            lines.append(f"  {q:11s} {v / 1e6:9.1f} M items/s")
        if ours in batch:
            lines.append(f"  {ours + ' batch':11s} {batch[ours] / 1e6:9.1f} M items/s (64 per call)")
        if best:
            lines.append(f"  {ours} / best peer ({best}): {tp[ours] / tp[best]:.2f}")
    rt = {r["queue"]: r["ns"] for r in rows if r["bench"] == "RoundTrip"}
    if rt:
        lines.append("Round-trip latency:")
        for q, ns in sorted(rt.items(), key=lambda kv: kv[1]):
            lines.append(f"  {q:11s} {ns:8.1f} ns")
    return lines


def _plot(rows: list[dict], path: Path) -> None:
    fig, axes = pyplot().subplots(1, 2, figsize=(11, 4))
    for ax, producers in zip(axes, (1, 2)):
        sel = [r for r in rows if r["bench"] in ("Throughput", "ThroughputBatch") and r["producers"] == producers]
        names = [r["queue"] + (" batch" if r["bench"] == "ThroughputBatch" else "") for r in sel]
        ax.barh(names, [r["items_per_s"] / 1e6 for r in sel],
                color=["tab:orange" if n.startswith("Our") else "tab:blue" for n in names])
        ax.set_xscale("log")
        ax.set_xlabel("M items / s (log)")
        ax.set_title(f"{producers} producer(s), 1 consumer")
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def run(args) -> int:
    binary = _find_binary(args.binary)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([str(binary), f"--benchmark_filter={args.filter}", "--benchmark_format=json"],
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise UserError(f"{binary} failed: {proc.stderr.strip()[-500:]}")
    report = json.loads(proc.stdout)
    rows = parse(report)
    write_json(out / "queues.json", {"context": report.get("context"), "rows": rows}, indent=2)
    _plot(rows, out / "queues.png")
    print("\n".join(summarise(rows)))
    print(f"wrote {out / 'queues.json'} and {out / 'queues.png'}")
    return 0

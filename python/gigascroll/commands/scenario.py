"""`gigascroll scenario NAME`: the exhibition scenarios of VT-mobile-VR §5 (results JSON, plots,
a Markdown report and frames as PNG in --out)."""

from __future__ import annotations

from pathlib import Path

from ..errors import UserError


def register(sub) -> None:
    from ..scenarios import SCENARIOS
    p = sub.add_parser("scenario", help="run an exhibition scenario (VT-mobile-VR §5)",
                       description="single: one scroll with eyes and magnifier (Tables 2, 3); "
                       "multi: 8-40 paintings on tables (Fig. 11, Table 5); sweep: tile totals "
                       "at a static camera against Ma VT and LOD mapping (Fig. 12); latency: "
                       "display latency after a stop.")
    p.add_argument("name", metavar="NAME", help=" | ".join(SCENARIOS))
    p.add_argument("--quick", action="store_true", help="scaled-down run (seconds; used by tests)")
    p.add_argument("--out", default=None,
                   help="output directory (default: next to --pack, PACK-scenarios; without "
                        "--pack, scenario-out in the working directory)")
    p.add_argument("--cache", default=None,
                   help="where test packs are kept between runs (default OUT/cache)")
    p.add_argument("--threshold", type=int, default=16,
                   help="direct loading: tiles issued per frame (default 16)")
    p.add_argument("--methods", default=None,
                   help="comma-separated methods (default: the scenario's set)")
    p.add_argument("--pack", default=None, help="use this pack instead of building one")
    p.add_argument("--path", default=None, help="camera path JSON instead of the scenario's")
    p.add_argument("--duration", type=float, default=None,
                   help="seconds of camera motion in a full run (default: the scenario's)")
    p.add_argument("--threads", type=int, default=0, help="worker threads (0: all cores)")
    p.add_argument("--no-pace", action="store_true", help="do not sleep to 90 Hz frame times")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..scenarios import SCENARIOS, Options, run_scenario
    if args.name not in SCENARIOS:
        raise UserError(f"unknown scenario {args.name!r}; choose from {', '.join(SCENARIOS)}")
    methods = None
    if args.methods is not None:
        methods = tuple(m.strip() for m in args.methods.split(",") if m.strip())
        if not methods:
            raise UserError("--methods is empty")
    if args.threads < 0:
        raise UserError("--threads must be >= 0")
    from ..outputs import beside
    if args.out is None:
        args.out = str(beside(args.pack, "scenarios") if args.pack else Path("scenario-out"))
    opts = Options(quick=args.quick, out=Path(args.out),
                   cache=Path(args.cache) if args.cache else None, threshold=args.threshold,
                   methods=methods, pack=Path(args.pack) if args.pack else None,
                   path=Path(args.path) if args.path else None, threads=args.threads,
                   pace=not args.no_pace, duration=args.duration)
    res = run_scenario(args.name, opts)
    report = Path(args.out).resolve() / f"{args.name}.md"
    failed = [k for k, ok in res.get("checks", {}).items() if ok is False]
    print(f"{args.name}: report {report}, results {report.with_suffix('.json')}")
    for k in failed:
        print(f"  check failed: {k}")
    return 1 if failed else 0

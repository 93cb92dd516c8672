"""The exhibition scenarios of VT-mobile-VR §5 (issue 4 §5): `single`, `multi`, `sweep`, `latency`.
Each writes NAME.json (results), NAME.md (report) and PNG plots and frames into the output
directory; `quick=True` runs a scaled-down version (tests run those and check their
invariants); full runs are the benchmarks recorded in bench/RESULTS.md."""

from __future__ import annotations

from .common import Options

__all__ = ["SCENARIOS", "Options", "run_scenario"]

SCENARIOS = ("single", "multi", "sweep", "latency")


def run_scenario(name: str, opts: Options | None = None, **kw) -> dict:
    if name not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; choose from {', '.join(SCENARIOS)}")
    from . import latency, multi, single, sweep
    opts = opts or Options(**kw)
    opts.out.mkdir(parents=True, exist_ok=True)
    return {"single": single, "multi": multi, "sweep": sweep, "latency": latency}[name].run(opts)

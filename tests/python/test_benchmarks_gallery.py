"""The gallery benchmark's comparison logic: the Pareto front and the fastest configuration
per target error against brute force, Mitsuba's time to an error against its ladder."""

import math

import numpy as np
import pytest

from gigascroll.benchmarks.gallery import (_time_to_error, compare_with_mitsuba, fastest_reaching,
                                           pareto_front)


def _configs(seed=0, n=60):
    rng = np.random.default_rng(seed)
    return [{"total_seconds": float(t), "relmse": float(e), "id": i}
            for i, (t, e) in enumerate(zip(rng.uniform(0.01, 5, n), rng.uniform(1e-3, 1e-1, n)))]


def test_pareto_front_is_the_set_no_configuration_dominates():
    cs = _configs()
    front = pareto_front(cs)
    dominated = {c["id"] for c in cs
                 if any(o["total_seconds"] <= c["total_seconds"] and o["relmse"] <= c["relmse"] and o is not c
                        and (o["total_seconds"], o["relmse"]) != (c["total_seconds"], c["relmse"]) for o in cs)}
    assert {c["id"] for c in front} == {c["id"] for c in cs} - dominated
    assert [c["total_seconds"] for c in front] == sorted(c["total_seconds"] for c in front)
    assert [c["relmse"] for c in front] == sorted((c["relmse"] for c in front), reverse=True)


def test_fastest_reaching_matches_brute_force_and_lies_on_the_front():
    cs = _configs(1)
    front_ids = {c["id"] for c in pareto_front(cs)}
    for error in np.geomspace(5e-4, 0.2, 40):
        best = fastest_reaching(cs, error)
        ok = [c for c in cs if c["relmse"] <= error]
        if not ok:
            assert best is None
            continue
        assert best["total_seconds"] == min(c["total_seconds"] for c in ok)
        assert best["id"] in front_ids


def test_time_to_error_interpolates_the_ladder_in_log_log():
    # Mitsuba's error falls as 1/spp and time grows as spp: time = c / error exactly.
    ladder = [{"spp": s, "seconds": 0.05 * s, "relmse": 2.0 / s} for s in (1, 4, 16, 64)]
    for error in np.geomspace(2.0 / 64, 2.0, 17):
        assert _time_to_error(ladder, error) == pytest.approx(0.1 / error, rel=1e-9)
    assert _time_to_error(ladder, 1e-3) is None          # below the ladder: not reached
    assert _time_to_error(ladder, 10.0) == 0.05          # above: its cheapest run


def test_compare_with_mitsuba_gives_speedups_and_bounds():
    ladder = [{"spp": s, "seconds": 0.05 * s, "relmse": 2.0 / s} for s in (1, 4, 16, 64)]
    cs = [{"total_seconds": 0.1, "relmse": 0.1}, {"total_seconds": 1.0, "relmse": 0.01}]
    rows = compare_with_mitsuba(cs, ladder)
    by_error = {r["relmse"]: r for r in rows}
    assert by_error[0.5]["speedup"] == pytest.approx(0.2 / 0.1)          # 4 spp, our 0.1 s config
    assert by_error[0.1]["speedup"] == pytest.approx((0.1 / 0.1) / 0.1)  # interpolated: 1 s
    r = by_error[0.01]                                                    # below the ladder
    assert r["mitsuba_seconds"] is None and r["speedup"] is None
    assert r["speedup_at_least"] == pytest.approx(3.2 / 1.0)
    assert math.isclose(by_error[2.0 / 64]["ours"]["total_seconds"], 1.0)

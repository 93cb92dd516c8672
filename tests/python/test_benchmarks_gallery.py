"""The gallery benchmark's comparison logic: the Pareto front and the fastest configuration
per target error against brute force, Mitsuba's time to an error against its ladder."""

import math

import numpy as np
import pytest

from gigascroll.benchmarks.gallery import (_time_to_error, apply_repeats, compare_with_mitsuba, fastest_reaching,
                                           ladder_points_used, pareto_front, retime,
                                           retime_plan)


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


def _ladder():
    return [{"spp": s, "seconds": 0.05 * s, "relmse": 2.0 / s} for s in (1, 4, 16, 64)]


def test_ladder_points_used_are_the_points_the_single_run_time_comes_from():
    ladder = _ladder()
    cs = _configs(2, 40)
    for row in compare_with_mitsuba(cs, ladder):
        used = ladder_points_used(row, ladder)
        if row["mitsuba_spp"] is not None:
            assert used == [row["mitsuba_spp"]]
        elif row["mitsuba_seconds"] is None:
            assert used == [64]                               # below the ladder: its largest run
        else:
            # Interpolating on the used points alone gives the single run's time.
            sub = [l for l in ladder if l["spp"] in used]
            assert _time_to_error(sub, row["relmse"]) == pytest.approx(row["mitsuba_seconds"], rel=1e-12)
            assert len(used) == 2 or row["relmse"] > 2.0      # bracketed, or above the ladder's worst


def test_retime_interleaves_and_times_each_chosen_configuration_and_point():
    ladder = _ladder()
    cs = _configs(3, 30)
    rows = compare_with_mitsuba(cs, ladder)
    log = []
    ours, mitsuba = retime(rows, ladder, lambda c: log.append(("o", c["id"])) or 1.0,
                           lambda s: log.append(("m", s)) or 2.0, repeats=3)
    chosen = {r["ours"]["id"] for r in rows if r["ours"] is not None}
    spps = {s for r in rows if r["ours"] is not None for s in ladder_points_used(r, ladder)}
    assert sorted(log) == sorted([("o", i) for i in chosen] * 3 + [("m", s) for s in spps] * 3)
    rounds = [log[i * len(log) // 3:(i + 1) * len(log) // 3] for i in range(3)]
    assert rounds[1] == rounds[0][::-1] and rounds[2] == rounds[0]  # every other round reversed
    kinds = [k for k, _ in rounds[0]]
    n = min(kinds.count("o"), kinds.count("m"))
    assert n > 0 and all(kinds[i] != kinds[i + 1] for i in range(2 * n - 1))  # ours and Mitsuba's alternate
    assert all(len(v) == 3 for v in list(ours.values()) + list(mitsuba.values()))


def test_retime_gives_cheap_jobs_more_rounds_still_interleaved():
    """Jobs whose single timing is at most cheap_seconds (a config's total_seconds, a ladder
    point's seconds) run cheap_repeats rounds, the others repeats; in the rounds after the
    expensive jobs stopped the cheap ones keep their order, reversed every other round."""
    ladder = _ladder()
    cs = _configs(3, 30)
    rows = compare_with_mitsuba(cs, ladder)
    log = []
    ours, mitsuba = retime(rows, ladder, lambda c: log.append(("o", id(c))) or 1.0,
                           lambda s: log.append(("m", s)) or 2.0, repeats=3, cheap_repeats=7,
                           cheap_seconds=0.5)
    chosen = {id(r["ours"]): r["ours"] for r in rows if r["ours"] is not None}
    spps = {s for r in rows if r["ours"] is not None for s in ladder_points_used(r, ladder)}
    seconds = {l["spp"]: l["seconds"] for l in ladder}
    cheap_o = {k for k, c in chosen.items() if c["total_seconds"] <= 0.5}
    cheap_m = {s for s in spps if seconds[s] <= 0.5}
    assert cheap_o and cheap_m and (len(cheap_o) < len(chosen) or len(cheap_m) < len(spps))
    for k in chosen:
        assert len(ours[k]) == (7 if k in cheap_o else 3)
    for s in spps:
        assert len(mitsuba[s]) == (7 if s in cheap_m else 3)
    # Rounds 4-7 hold the cheap jobs alone, alternating in direction.
    per_round = len(cheap_o) + len(cheap_m)
    tail = log[len(log) - 4 * per_round:]
    r3, r4, r5 = tail[:per_round], tail[per_round:2 * per_round], tail[2 * per_round:3 * per_round]
    assert r4 == r3[::-1] and r5 == r3
    assert {j for j in r3} == {("o", k) for k in cheap_o} | {("m", s) for s in cheap_m}
    # The plan the bench's progress bar is sized from counts exactly the calls made.
    assert sum(n for *_, n in retime_plan(rows, ladder, 3, 7, cheap_seconds=0.5)[1]) == len(log)


def test_apply_repeats_gives_ratios_of_medians_against_brute_force():
    rng = np.random.default_rng(4)
    ladder = _ladder()
    cs = _configs(5, 30)
    rows = compare_with_mitsuba(cs, ladder)
    compared = 0

    def ours(c):
        return c["total_seconds"] * rng.uniform(0.5, 2.0)

    def mits(s):
        return 0.05 * s * rng.uniform(0.5, 2.0)

    ours_t, mits_t = retime(rows, ladder, ours, mits, repeats=5)
    out = apply_repeats(rows, ladder, ours_t, mits_t)
    assert len(out) == len(rows)
    for row, new in zip(rows, out):
        if row["ours"] is None:
            assert new == row
            continue
        times = ours_t[id(row["ours"])]
        assert new["ours_median_seconds"] == sorted(times)[2]          # median of 5
        med = {s: sorted(v)[2] for s, v in mits_t.items()}
        if row["mitsuba_seconds"] is None:
            assert new["speedup_at_least_median"] == pytest.approx(med[64] / sorted(times)[2])
            continue
        # Brute force: the log-log line through the used points' median times.
        used = ladder_points_used(row, ladder)
        if len(used) == 1:
            m = med[used[0]]
        else:
            (e0, t0), (e1, t1) = sorted((2.0 / s, med[s]) for s in used)
            w = math.log(row["relmse"] / e0) / math.log(e1 / e0)
            m = t0 ** (1 - w) * t1 ** w
        assert new["mitsuba_median_seconds"] == pytest.approx(m, rel=1e-9)
        assert new["speedup_median"] == pytest.approx(m / sorted(times)[2], rel=1e-9)
        lo, hi = new["speedup_range"]
        assert lo <= new["speedup_median"] <= hi
        assert lo == pytest.approx(min(
            _time_to_error([{**l, "seconds": min(mits_t[l["spp"]])} for l in ladder if l["spp"] in used],
                           row["relmse"]) / t for t in [max(times)]), rel=1e-9)
        compared += 1
    assert compared > 3


@pytest.mark.parametrize("args, message", [
    (("--timing-repeats", "0"), "--timing-repeats"),
    (("--cheap-repeats", "0"), "--cheap-repeats"),
    (("--cheap-repeats", "-3"), "--cheap-repeats"),
    (("--disc-photons", "x"), "--disc-photons"),
    (("--disc-photons", "31"), "powers of two up to 2^30"),
    (("--coarse-photons", "x"), "--coarse-photons"),
    (("--coarse-photons", "0"), "--coarse-photons needs positive integers"),
    (("--coarse-photons", "31"), "powers of two up to 2^30"),
])
def test_bad_options_are_one_line_errors(gigascroll_cli, tmp_path, args, message):
    r = gigascroll_cli("bench", "gallery", "--out", tmp_path, *args)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr

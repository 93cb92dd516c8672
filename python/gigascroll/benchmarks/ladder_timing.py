"""Mitsuba's time to an error along its spp ladder, and the interleaved re-timing of our chosen
configurations against the ladder points they are compared with (`gigascroll bench gallery`'s
front and its quality knob's curve)."""

from __future__ import annotations

import math

import numpy as np

# Re-timed jobs (ours or a Mitsuba ladder point) whose single timing is at most this many
# seconds get --cheap-repeats re-timings instead of --timing-repeats.
CHEAP_SECONDS = 0.05


def ladder_points_used(row: dict, ladder: list[dict]) -> list[int]:
    """The spp of the ladder points a target row's Mitsuba time comes from: its own point,
    the two it is interpolated between, the cheapest (above the ladder's worst error) or the
    largest (below the ladder: the lower bound)."""
    if row["mitsuba_spp"] is not None:
        return [row["mitsuba_spp"]]
    pts = sorted((l["relmse"], l["spp"]) for l in ladder)
    error = row["relmse"]
    if row["mitsuba_seconds"] is None or error < pts[0][0]:
        return [max(ladder, key=lambda l: l["seconds"])["spp"]]
    for (e0, s0), (e1, s1) in zip(pts, pts[1:]):
        if e0 <= error <= e1:
            return sorted({s0, s1})
    return [pts[-1][1]]


def _interleaved(a: list, b: list) -> list:
    """a[0], b[0], a[1], b[1], ... then the longer list's rest."""
    out = []
    for i in range(max(len(a), len(b))):
        out += a[i:i + 1] + b[i:i + 1]
    return out


def retime_plan(rows: list[dict], ladder: list[dict], repeats: int, cheap_repeats: int | None = None,
                cheap_seconds: float = CHEAP_SECONDS):
    """What retime() runs: ({id(config): config} of the configurations chosen in `rows`,
    [(kind, key, rounds)] of the jobs in their interleaved order, kind "ours" (key the
    config's id) or "mitsuba" (key its spp)). Jobs whose single timing (the config's
    total_seconds, the ladder point's seconds) is at most `cheap_seconds` get `cheap_repeats`
    rounds when that is more than `repeats`: a millisecond job's time moves by tens of percent
    from call to call (the other process's threads, cold caches), so a median of 3 is a coin
    toss there, and 30 of them cost a fraction of a second."""
    configs, spps = {}, set()
    for row in rows:
        if row["ours"] is not None:
            configs.setdefault(id(row["ours"]), row["ours"])
            spps.update(ladder_points_used(row, ladder))
    seconds = {l["spp"]: l["seconds"] for l in ladder}
    cheap = max(repeats, cheap_repeats or 0)
    jobs = _interleaved([("mitsuba", s) for s in sorted(spps)], [("ours", k) for k in configs])
    return configs, [(kind, key, cheap if (configs[key]["total_seconds"] if kind == "ours" else seconds[key])
                      <= cheap_seconds else repeats) for kind, key in jobs]


def retime(rows: list[dict], ladder: list[dict], time_ours, time_mitsuba, repeats: int,
           cheap_repeats: int | None = None, cheap_seconds: float = CHEAP_SECONDS):
    """Re-times every configuration chosen in `rows` (compare_with_mitsuba's, `ours` not None)
    with time_ours(config) -> seconds, and every ladder point those rows use with
    time_mitsuba(spp) -> seconds, in rounds, ours and Mitsuba's interleaved, every other round
    in reverse order (so drifts in the machine's load fall on both alike); each job for its
    retime_plan() number of rounds. Returns ({id(config): [seconds, ...]}, {spp: [seconds,
    ...]}), each list in the order timed."""
    configs, jobs = retime_plan(rows, ladder, repeats, cheap_repeats, cheap_seconds)
    ours = {key: [] for kind, key, _ in jobs if kind == "ours"}
    mitsuba = {key: [] for kind, key, _ in jobs if kind == "mitsuba"}
    for r in range(max([n for *_, n in jobs], default=0)):
        for kind, key, rounds in (jobs if r % 2 == 0 else jobs[::-1]):
            if r >= rounds:
                continue
            if kind == "ours":
                ours[key].append(float(time_ours(configs[key])))
            else:
                mitsuba[key].append(float(time_mitsuba(key)))
    return ours, mitsuba


def apply_repeats(rows: list[dict], ladder: list[dict], ours_times: dict, mitsuba_times: dict) -> list[dict]:
    """The target rows with the repeats' medians: Mitsuba's time at each target from the
    median times of its ladder points (interpolated as before, errors from the single run),
    ours the median of the chosen configuration's repeats, the speedup their ratio; the
    spread as the speedup's range (Mitsuba's fastest against our slowest repeat, and the
    reverse). Rows without repeats (not reached) are returned unchanged."""
    def ladder_with(stat):
        return [{**l, "seconds": stat(mitsuba_times[l["spp"]])} for l in ladder if mitsuba_times.get(l["spp"])]

    med = ladder_with(lambda t: float(np.median(t)))
    lo, hi = ladder_with(min), ladder_with(max)
    out = []
    for row in rows:
        row = dict(row)
        times = ours_times.get(id(row["ours"])) if row["ours"] is not None else None
        if times:
            used = ladder_points_used(row, ladder)
            ours_med = float(np.median(times))
            row["ours_repeat_seconds"] = times
            row["ours_median_seconds"] = ours_med
            row["mitsuba_repeat_seconds"] = {str(s): mitsuba_times[s] for s in used}
            if row["mitsuba_seconds"] is not None:
                m, m_lo, m_hi = (_time_to_error([x for x in lad if x["spp"] in used], row["relmse"])
                                 for lad in (med, lo, hi))
                row.update(mitsuba_median_seconds=m, speedup_median=m / ours_med,
                           speedup_range=[m_lo / max(times), m_hi / min(times)])
            else:
                b = [float(np.median(mitsuba_times[s])) for s in used][0]
                row.update(mitsuba_median_seconds=None, mitsuba_median_bound_seconds=b,
                           speedup_median=None, speedup_at_least_median=b / ours_med,
                           speedup_range=None)
        out.append(row)
    return out


def _time_to_error(ladder: list[dict], error: float) -> float | None:
    """Seconds Mitsuba needs for `error` (relMSE), log-log interpolated along its ladder;
    None when even its largest spp does not reach it."""
    pts = sorted((l["relmse"], l["seconds"]) for l in ladder)
    if error < pts[0][0]:
        return None
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 <= error <= e1:
            if e1 == e0:
                return t0
            w = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    return pts[-1][1]  # our error is above the ladder's worst: its cheapest run already beats it

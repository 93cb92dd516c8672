"""Every scenario (gigascroll.scenarios) in quick mode: its invariants (methods agree, nothing lost in loading, the
frame salt, latency bounds, the magnifier sharp only with its requests), its outputs, and the
CLI's answers to bad input."""

import json
import math

import pytest

from gigascroll import cli
from gigascroll.scenarios import SCENARIOS, Options, run_scenario


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("scenario-cache")


@pytest.fixture(scope="module")
def results(tmp_path_factory, cache):
    out = tmp_path_factory.mktemp("scenarios")
    return out, {n: run_scenario(n, Options(quick=True, out=out, cache=cache))
                 for n in SCENARIOS}


@pytest.mark.parametrize("name", SCENARIOS)
def test_quick_scenario_invariants_hold(results, name):
    out, res = results
    checks = res[name]["checks"]
    assert checks, name
    failed = [k for k, ok in checks.items() if ok is False]
    assert not failed, f"{name}: {failed}"
    data = json.loads((out / f"{name}.json").read_text())
    assert data["checks"] == checks
    report = (out / f"{name}.md").read_text()
    for line in report.splitlines():
        if line.startswith("!["):
            assert (out / line.split("(")[-1].rstrip(")")).stat().st_size > 0


def test_single_tables(results):
    res = results[1]["single"]
    assert [r["method"] for r in res["table2"]] == ["cpu-async", "flag-array", "hash"]
    assert [r["strategy"] for r in res["table3"]] == ["direct", "mip-by-mip"]
    # Synchronous methods answer in the frame they are asked; the CPU-async worker later.
    for r in res["table2"]:
        assert 0 <= r["hit_rate"] <= 1
        if r["method"] != "cpu-async":
            assert r["latency_frames"] == 0
    m = res["magnifier"]
    assert m["hit_rate_with_requests"] == 1.0 > m["hit_rate_without_requests"]
    assert res["salt"]["lost_twice_in_a_row"] == 0


def test_sweep_baselines_and_lod_memory(results):
    rows = results[1]["sweep"]["rows"]
    assert {r["method"] for r in rows} == {"basic", "ma-vt", "lod-mapping", "hash"}
    for r in rows:
        if r["method"] == "lod-mapping":
            # A whole level per painting: at least the tiles the view needs.
            assert r["lod_memory_mb"] > 0
        assert r["feedback_ms"] == 0 or r["method"] in ("basic", "hash")


def test_latency_bounds(results):
    rows = {r["method"]: r for r in results[1]["latency"]["rows"]}
    assert 1 <= rows["hash"]["display_latency_frames"] <= 5
    assert all(r["display_latency_frames"] is not None for r in rows.values())


def _cli(capsys, *argv):
    code = cli.main(["scenario", *argv])
    return code, capsys.readouterr().err


def test_bad_input(tmp_path, capsys, cache, results):
    code, err = _cli(capsys, "gallery", "--quick", "--out", str(tmp_path))
    assert code == 2 and "unknown scenario" in err
    code, err = _cli(capsys, "single", "--quick", "--methods", "magic", "--out", str(tmp_path))
    assert code == 2 and "unknown method" in err
    for t in ("0", "-3"):
        code, err = _cli(capsys, "single", "--quick", "--threshold", t, "--out", str(tmp_path))
        assert code == 2 and "threshold" in err
    code, err = _cli(capsys, "latency", "--quick", "--duration", "nan", "--out", str(tmp_path))
    assert code == 2 and "duration" in err
    # The quick single pack has one painting; the room needs sixteen.
    one = cache / "pattern-12000x1600-raw.pack"
    assert one.exists()
    code, err = _cli(capsys, "multi", "--quick", "--pack", str(one), "--out", str(tmp_path))
    assert code == 2 and "missing" in err
    code, err = _cli(capsys, "single", "--quick", "--pack", str(tmp_path / "none.pack"),
                     "--out", str(tmp_path))
    assert code == 2 and "no such pack" in err
    bad = tmp_path / "path.json"
    bad.write_text(json.dumps({"position": [[0.5, 1.5, -0.4], [math.nan, 1.5, -0.4]],
                               "forward": [[0, 0, 1]] * 2, "up": [[0, 1, 0]] * 2}))
    code, err = _cli(capsys, "latency", "--quick", "--path", str(bad), "--cache", str(cache),
                     "--out", str(tmp_path))
    assert code == 2 and "NaN" in err
    assert not (tmp_path / "latency.md").exists()  # no report that looks complete


def test_cli_runs_a_scenario(tmp_path, capsys, cache):
    code = cli.main(["scenario", "latency", "--quick", "--methods", "hash,ma-vt", "--cache",
                     str(cache), "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0 and "report" in out
    rows = json.loads((tmp_path / "latency.json").read_text())["rows"]
    assert [r["method"] for r in rows] == ["hash", "ma-vt"]

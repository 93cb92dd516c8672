"""`gigascroll bench bc1` (gigascroll.benchmarks.bc1): a small end-to-end run whose figures
must make sense against what they measure, and its answers to bad parameters."""

import json

import pytest

from gigascroll import cli


def test_bench_bc1_small_run(tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["bench", "bc1", "--quick",
                   "--cache", str(tmp_path / "cache"), "--out", str(out)])
    assert rc == 0
    result = json.loads((out / "bc1.json").read_text())
    q = result["quality"]
    assert {r["painting"] for r in q} == {"qianli_jiangshan", "table4_1"}  # --quick: two
    first = [r for r in q if r["painting"] == "qianli_jiangshan"]
    assert [r["level"] for r in first] == list(range(len(first)))
    assert all(25 < r["psnr_db"] < 60 for r in q)  # lossy, but a working encoder
    assert all(0 < r["flip"] < 0.3 for r in q if r["flip"] == r["flip"])  # NaN: too small
    assert all(r["cost_ratio"] > 0 for r in result["sampling"]["rows"])
    for r in result["hits"]["rows"]:  # 6x the slots in the same bytes never hit less
        assert r["bc1_slots"][1] == 6 * r["raw_slots"][1]
        if r["raw_hit_rate"] is not None:
            assert r["bc1_hit_rate"] >= r["raw_hit_rate"]
    assert "PSNR" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["--parts", "speed"], ["--scale", "0"], ["--repeat", "0"]])
def test_bench_bc1_rejects_bad_parameters(tmp_path, capsys, argv):
    rc = cli.main(["bench", "bc1", "--cache", str(tmp_path), "--out", str(tmp_path), *argv])
    assert rc == 2
    assert "error" in capsys.readouterr().err

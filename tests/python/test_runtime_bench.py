"""`gigascroll bench loader` and `bench queues`: a small end-to-end run and the report parsing."""

import json

import pytest

from gigascroll import cli
from gigascroll.benchmarks import queues


def test_bench_loader_small_run(tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["bench", "loader", "--width", "3000", "--height", "400", "--tiles", "600",
                   "--repeat", "1", "--configs", "locked:2,lockfree:1", "--codecs", "raw,zstd",
                   "--samples", "20000", "--sample-size", "1024x512",
                   "--cache", str(tmp_path / "cache"), "--out", str(out)])
    assert rc == 0
    result = json.loads((out / "loader.json").read_text())
    assert set(result["loading"]) == {"raw", "zstd"}
    for codec in ("raw", "zstd"):
        rows = result["loading"][codec]["rows"]
        assert [r["config"] for r in rows] == ["locked:2", "lockfree:1"]
        assert all(r["seconds"] > 0 for r in rows)
        assert result["loading"][codec]["requests_per_frame"] > 0
    for r in result["sampling"]["rows"]:
        assert r["max_abs_difference"] < 1e-3  # VT and plain texture agree on every sample
    assert (out / "loader.png").stat().st_size > 0
    assert "physical limit" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [["--configs", "spinning:2"], ["--codecs", "lz4"], ["--tiles", "0"],
                                  ["--fov", "180"]])
def test_bench_loader_rejects_bad_parameters(tmp_path, capsys, argv):
    rc = cli.main(["bench", "loader", "--cache", str(tmp_path), "--out", str(tmp_path), *argv])
    assert rc == 2
    assert "error" in capsys.readouterr().err


def test_queue_report_parsing():
    def bench(name, **kw):
        return {"name": name, "aggregate_name": "median", "real_time": kw.get("t", 1.0),
                "time_unit": kw.get("unit", "ms"), **({"items_per_second": kw["ips"]} if "ips" in kw else {})}
    report = {"benchmarks": [
        bench("BM_Throughput<OurSpsc>/1/iterations:8/repeats:5/real_time", ips=5e7),
        bench("BM_Throughput<BoostSpsc>/1/iterations:8/repeats:5/real_time", ips=4e7),
        bench("BM_Throughput<OurMpsc>/2/iterations:8/repeats:5/real_time", ips=1e7),
        bench("BM_Throughput<CQueue>/2/iterations:8/repeats:5/real_time", ips=2e7),
        bench("BM_RoundTrip<OurSpsc>/repeats:5/real_time", t=90.0, unit="ns"),
        {"name": "BM_RoundTrip<OurSpsc>/repeats:5/real_time_mean", "aggregate_name": "mean",
         "real_time": 1e9, "time_unit": "ns"},
    ]}
    rows = queues.parse(report)
    assert len(rows) == 5
    text = "\n".join(queues.summarise(rows))
    assert "OurSpsc / best peer (BoostSpsc): 1.25" in text
    assert "OurMpsc / best peer (CQueue): 0.50" in text
    assert "90.0 ns" in text


def test_bench_queues_missing_binary(tmp_path, capsys):
    rc = cli.main(["bench", "queues", "--binary", str(tmp_path / "nope"), "--out", str(tmp_path)])
    assert rc == 2
    assert "no such benchmark executable" in capsys.readouterr().err

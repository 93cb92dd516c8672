"""`gigascroll bench queues` (gigascroll.benchmarks.queues): the report parsing and a missing
benchmark executable."""

from gigascroll import cli
from gigascroll.benchmarks import queues


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

"""`gigascroll bench views` (gigascroll.benchmarks.views) runs end to end in quick mode and
rejects bad arguments."""

import json

from gigascroll import cli


def test_bench_views_quick_parts(tmp_path, capsys):
    assert cli.main(["bench", "views", "--quick", "--part", "latency", "--part", "losses",
                     "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "views_latency_losses.json").read_text())
    assert data["async_latency"]["frames"] == 20
    assert data["async_latency"]["min"] >= 0
    losses = {h["table_bits"]: h for h in data["hash_losses"]}
    assert losses[12]["lost_per_frame"] >= losses[18]["lost_per_frame"]
    assert "Hash losses" in capsys.readouterr().out


def test_bench_views_bad_arguments(tmp_path, capsys):
    assert cli.main(["bench", "views", "--frames", "0", "--out", str(tmp_path)]) == 2
    assert "must be >= 1" in capsys.readouterr().err


def test_bench_views_quick_pace(tmp_path, capsys):
    # The flat-out loop reports every stage and a wall time that covers the stages.
    assert cli.main(["bench", "views", "--quick", "--part", "pace", "--out", str(tmp_path)]) == 0
    p = json.loads((tmp_path / "views_pace.json").read_text())["pace"]
    stages = sum(p[s + "_ms"] for s in ("feedback", "processing", "issue", "drain", "update",
                                        "display"))
    assert abs(stages - p["stage_ms_sum"]) < 1e-6 * max(1.0, stages)
    assert p["wall_ms"] >= 0.9 * p["stage_ms_sum"]
    # The hit rate depends on how far the loader threads got in 19 flat-out frames (0 on a
    # loaded host is legal); that tiles were requested does not.
    assert 0 <= p["hit_rate"] <= 1 and p["frames"] == 19 and p["requests_per_frame"] > 0
    assert "Frame loop flat out" in capsys.readouterr().out
    assert (tmp_path / "views_pace.png").stat().st_size > 0

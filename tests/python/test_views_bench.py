"""`gigascroll bench views` runs end to end in quick mode and rejects bad arguments."""

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

"""`gigascroll bench pack` (gigascroll.benchmarks.pack): a small run against libvips."""

import json

import pytest


def test_bench_pack_smoke(tmp_path, gigascroll_cli):
    pytest.importorskip("pyvips")
    r = gigascroll_cli("bench", "pack", "--width", 700, "--height", 260, "--workdir", tmp_path)
    assert r.returncode == 0, r.stderr
    result = json.loads((tmp_path / "bench_pack.json").read_text())
    assert set(result["builders"]) == {"gigascroll", "libvips dzsave"}
    assert result["speed_ratio"] > 0
    assert (tmp_path / "bench_pack.png").stat().st_size > 0
    # outputs removed, the synthesized input cached
    assert sorted(f.name for f in tmp_path.iterdir()) == [
        "bench_pack.json", "bench_pack.png", "ink-700x260.tif"]

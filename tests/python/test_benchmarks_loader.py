"""`gigascroll bench loader` (gigascroll.benchmarks.loader): a small end-to-end run and its
answers to bad parameters."""

import json

import pytest

from gigascroll import cli


def test_bench_loader_small_run(tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["bench", "loader", "--width", "3000", "--height", "400", "--tiles", "600",
                   "--repeat", "1", "--configs", "locked:2,lockfree:1", "--codecs", "raw,zstd,bc1",
                   "--samples", "20000", "--sample-size", "1024x512",
                   "--cache", str(tmp_path / "cache"), "--out", str(out)])
    assert rc == 0
    result = json.loads((out / "loader.json").read_text())
    assert set(result["loading"]) == {"raw", "zstd", "bc1"}
    # zstd's own decode limit is measured; a bc1 pack's tiles are 1/6 of raw's and not decoded
    assert result["loading"]["zstd"]["decode_limit_tiles_per_s"] > 0
    assert result["loading"]["bc1"]["decode_limit_tiles_per_s"] is None
    assert result["loading"]["bc1"]["mean_tile_bytes"] * 6 == result["loading"]["raw"]["mean_tile_bytes"]
    for codec in ("raw", "zstd", "bc1"):
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

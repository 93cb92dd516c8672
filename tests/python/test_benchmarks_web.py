"""`gigascroll bench web --quick`: runs both servers under the same load, checks their bytes,
and writes its figures under "server" in results.json, keeping the file's other parts."""

import json


def test_bench_web_quick(tmp_path, gigascroll_cli):
    (tmp_path / "results.json").write_text(json.dumps({"client": {"kept": True}}))
    r = gigascroll_cli("bench", "web", "--quick", "--out", tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["client"] == {"kept": True}
    s = doc["server"]
    assert s["tiles"] > 10 and s["tile_bytes"] == 128 * 128 * 3
    for kind in ("static", "serve", "serve-batch"):
        assert len(s["runs"][kind]) == 1 and s["median"][kind]["tiles_per_s"] > 0
        run = s["runs"][kind][0]  # random tiles over the whole pack, not a few
        assert run["distinct_tiles"] >= min(s["tiles"], run["tiles_fetched"]) // 3
        m = s["median"][kind]
        assert abs(m["mb_per_s"] * 1e6 - m["tiles_per_s"] * s["tile_bytes"]) < 1e-6 * m["mb_per_s"] * 1e6
    assert s["ratio_serve_to_static"] == (s["median"]["serve"]["tiles_per_s"]
                                          / s["median"]["static"]["tiles_per_s"])
    assert "serve / static" in r.stdout


def test_bench_web_refuses_bad_options(tmp_path, gigascroll_cli):
    for args in (["--connections", "0"], ["--duration", "nan"], ["--batch", "65"]):
        r = gigascroll_cli("bench", "web", "--out", tmp_path, *args)
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "error" in r.stderr

"""`gigascroll bench exhibition-full` at 1/256 per axis (a smoke run of the full-size
benchmark): the pack holds 40 paintings, the eight scans stored once (its tile files are
those of a pack of the eight scans alone), the scans are the Table 4 sizes at that scale,
the multi and hall parts report sane figures, and a second run reuses scans and pack."""

import json
import math
from pathlib import Path

import pytest

from gigascroll import TilePack, build_pack
from gigascroll import views as v


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from subprocess import run as sp_run
    import sys
    root = tmp_path_factory.mktemp("exfull")

    def bench(*extra):
        r = sp_run([sys.executable, "-m", "gigascroll", "bench", "exhibition-full",
                    "--scale", "1/256", "--work", str(root / "work"), "--seconds", "0.2",
                    "--eye", "64x64", "--no-pace", "--workers", "1", *extra],
                   capture_output=True, text=True, timeout=600)
        return r
    r = bench("--out", str(root / "a.json"))
    assert r.returncode == 0, r.stderr[-2000:]
    return root, bench, json.loads((root / "a.json").read_text())


def test_the_pack_stores_eight_scans(run):
    root, _, res = run
    b = res["build"]
    assert (b["paintings"], b["stored_paintings"]) == (40, 8)
    work = root / "work" / "scale-1_256"
    pack = TilePack(work / "hall40.pack")
    scans = sorted((work / "scans").glob("scan*.tif"), key=lambda p: int(p.stem[4:]))
    assert [(p.width, p.height) for p in pack.paintings[:8]] == \
        [(-(-s.width // 256), -(-s.height // 256)) for s in v.TABLE4_PAINTINGS]
    assert [p.instance_of for p in pack.paintings] == [None] * 8 + [i % 8 for i in range(8, 40)]
    alone = build_pack(scans, root / "alone.pack", codec="zstd",
                       names=[p.name for p in pack.paintings[:8]])
    want = sum((Path(alone.path) / f).stat().st_size for f in alone.tile_files)
    assert b["pack_tiles_bytes"] == want
    assert b["pack_bytes"] < want + 64 * 1024       # plus the index and the manifest
    assert b["copies_estimate_bytes"] > 4 * want
    assert b["build_peak_rss_mb"] > 10 and b["build_s"] > 0


def test_the_walks_report(run):
    _, _, res = run
    frames = round(0.2 * v.FPS)
    assert [r["method"] for r in res["multi"]] == ["flag-array", "hash"]
    assert [r["frames"] for r in res["multi"]] == [frames, frames]
    assert res["hall"]["frames"] >= frames  # the walk's seven parts take two frames at least
    for r in res["multi"] + [res["hall"]]:
        assert 0 < r["hit_rate"] <= 1 and r["requests_per_frame"] > 0
        assert r["loaded_per_frame"] <= r["issued_per_frame"] <= 16
        assert math.isfinite(r["processing_ms"]) and r["processing_ms"] > 0


def test_a_second_run_reuses_the_pack(run):
    root, bench, _ = run
    r = bench("--out", str(root / "b.json"), "--parts", "build,multi", "--methods", "hash")
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads((root / "b.json").read_text())
    assert res["build"]["reused_pack"] and res["build"]["synth_s"] == 0
    assert [x["method"] for x in res["multi"]] == ["hash"] and "hall" not in res


@pytest.mark.parametrize("argv, match", [(["--scale", "1/3"], "--scale"),
                                         (["--scale", "2"], "--scale"),
                                         (["--scale", "x"], "--scale"),
                                         (["--parts", "walk"], "--parts"),
                                         (["--seconds", "nan"], "--seconds"),
                                         (["--workers", "0"], "--workers"),
                                         (["--eye", "10x10"], "--eye"),
                                         (["--eye", "ax2"], "--eye"),
                                         (["--methods", "hash,nope"], "--methods"),
                                         ([], "--scale")])  # required: a run may take hours
def test_bad_options(gigascroll_cli, tmp_path, argv, match):
    scale = [] if not argv else ["--scale", "1/256"]
    r = gigascroll_cli("bench", "exhibition-full", "--work", tmp_path / "w", "--out",
                       tmp_path / "r.json", *scale, *argv)
    assert r.returncode == 2 and match in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "w").exists()

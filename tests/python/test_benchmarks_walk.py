"""`gigascroll bench walk` at a tiny size: the stereo part writes its display-against-bare-rays
figure consistently (ratio = display / bare per pixel), and bad parts or sizes exit 2."""

import json
import math

import pytest

from gigascroll.cli import main


def test_stereo_part_writes_a_consistent_ratio(tmp_path, small_scroll_pack):
    out = tmp_path / "walk.json"
    rc = main(["bench", "walk", "--pack", str(small_scroll_pack.path), "--parts", "stereo",
               "--eye", "40x44,48x52", "--repeats", "1", "--photons", "4000",
               "--out", str(out)])
    assert rc == 0
    r = json.loads(out.read_text())
    rows = r["stereo_display_vs_rays"]
    assert [row["eye"] for row in rows] == ["40x44", "48x52"]
    assert r["display_vs_rays"] == []  # the per-eye part was not asked for
    for row in rows:
        disp, bare = row["display_ns_per_pixel"], row["bare_rays_ns_per_pixel"]
        assert math.isfinite(disp) and disp > 0 and math.isfinite(bare) and bare > 0
        assert math.isfinite(row["ratio"]) and row["ratio"] > 0
        assert row["ratio"] == pytest.approx(disp / bare, rel=1e-12)
        assert row["cpu_ratio"] is None or (math.isfinite(row["cpu_ratio"]) and row["cpu_ratio"] > 0)
        assert row["min_ratio"] is None or (math.isfinite(row["min_ratio"]) and row["min_ratio"] > 0)
        assert 0 < row["reused_share"] <= 1  # the right eye reuses left hits


@pytest.mark.parametrize("extra", [["--parts", "stereo,nonsense"], ["--eye", "0x0"],
                                   ["--eye", "48by52"], ["--eye", ","]])
def test_bad_parts_and_sizes_exit_2(tmp_path, small_scroll_pack, capsys, extra):
    out = tmp_path / "walk.json"
    rc = main(["bench", "walk", "--pack", str(small_scroll_pack.path), "--parts", "stereo",
               "--repeats", "1", "--photons", "4000", "--out", str(out), *extra])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gigascroll bench: error:") and "\n" not in err
    assert not out.exists()

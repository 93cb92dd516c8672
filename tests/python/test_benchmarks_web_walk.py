"""`gigascroll bench web`'s client walk (benchmarks/web_walk.py): its figures from a page's
per-frame log, a short real walk in headless chromium, and the option's refusals."""

import shutil

import pytest

from gigascroll.benchmarks.web_walk import _summary, walk_figures, walk_text

TILE_BYTES = 128 * 128 * 3


def test_summary_of_a_log():
    """Four walked frames and two after the stop, computed by hand."""
    # Frame 3 processed no readback (its request figures repeat frame 2's): not counted again.
    log = [{"frame": 10 + k, "t": 100.0 * k, "uploads": u, "bytes": b, "requests": r, "hits": h,
            "commands": 0, "inFlight": 0, "readbacks": rb}
           for k, (u, b, r, h, rb) in enumerate([(0, 0, 10, 10, 1), (2, 2 * TILE_BYTES, 10, 8, 2),
                                                  (1, 3 * TILE_BYTES, 20, 19, 3), (0, 3 * TILE_BYTES, 20, 19, 3),
                                                  (0, 3 * TILE_BYTES, 10, 10, 4), (0, 3 * TILE_BYTES, 10, 10, 5)])]
    f = _summary({"log": log, "walked": 4,
                  "stats": {"framesStopToExact": 2, "framesStopToConfirmed": 5, "exact": True}}, 50.0)
    assert f["frames"] == 4
    assert f["tiles_uploaded_per_frame"] == 0.75 and f["tiles_uploaded_per_frame_max"] == 2
    assert f["bytes_per_frame"] == 3 * TILE_BYTES / 3            # over the 3 frame intervals
    assert f["bytes_per_s_at_90hz"] == 90 * TILE_BYTES
    assert f["bytes_per_s_emulated"] == 3 * TILE_BYTES / 0.3     # 300 ms of walk
    assert f["hit_rate"] == 37 / 40 and f["requests_per_readback"] == 40 / 3 and f["readbacks"] == 3
    assert f["frames_stop_to_exact"] == 2 and f["frames_stop_to_confirmed"] == 5
    assert f["frame_time_walk_to_still"] == 100.0 / 50.0


@pytest.mark.skipif(shutil.which("chromium") is None, reason="chromium not installed")
def test_short_walk_in_chromium():
    """A 0.3 m walk (27 frames of a 90 Hz headset) with the magnifier: tiles stream (whole
    tiles' bytes), most requests hit, and the stop's view becomes exact."""
    pytest.importorskip("playwright")
    f = walk_figures(width=4000, height=200, size=(240, 136), metres=0.3)
    assert f["frames"] == 27 and f["exact_reached"]
    assert f["frames_stop_to_exact"] is not None and 0 <= f["frames_stop_to_exact"] <= 8
    assert f["bytes_per_frame"] * (f["frames"] - 1) % TILE_BYTES == 0
    assert 0 < f["hit_rate"] <= 1 and f["tiles_uploaded_per_frame_max"] <= 16
    assert "tiles uploaded a frame" in walk_text(f)
    assert f["gpu_ms_emulated"] is None or f["gpu_ms_emulated"] > 0
    assert "GPU time (timer query) / still frame time" in walk_text(f)


def test_walk_option_refused(tmp_path, gigascroll_cli):
    for value in ("nan", "-1", "11", "inf"):
        r = gigascroll_cli("bench", "web", "--quick", "--out", tmp_path, "--walk-metres", value)
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--walk-metres" in r.stderr, r.stderr

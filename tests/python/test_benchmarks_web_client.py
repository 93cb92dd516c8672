"""benchmarks/web_client.py: the client's feedback processing figures in headless chromium
(`gigascroll bench web`'s client part), on a small painting and a few frames."""

import pytest

from browser import browser, chromium_path  # noqa: F401 - fixtures


def test_feedback_figures(browser):  # noqa: F811 - the session's chromium
    from gigascroll.benchmarks.web_client import feedback_figures, format_figures

    f = feedback_figures(2000, 600, frames=12, browser=browser)
    # Both Quest 3 eyes at 1/8 and the magnifier at full size.
    assert f["feedback_pixels"] == [258 * 276, 258 * 276, 512 * 512]
    assert f["pixels_a_frame"] == 2 * 258 * 276 + 512 * 512
    assert f["requests_all_views"] > 0 and f["median_ms_all_views"] >= 0
    assert f["median_ms_naive_set"] > 0 and f["ratio_naive_to_ours"] > 0
    assert "median" in format_figures(f)


def test_feedback_figures_without_chromium(monkeypatch):
    from gigascroll.benchmarks import web_client

    monkeypatch.setattr(web_client.shutil, "which", lambda name: None)
    with pytest.raises(RuntimeError, match="chromium not found"):
        web_client.feedback_figures(100, 100, frames=1)

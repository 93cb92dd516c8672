"""The browser client's feedback processing time (`gigascroll bench web`'s client part for the
virtual texture): the JS time a frame takes to turn the feedback of both eyes of a Quest 3 at
1/8 resolution (2064 x 2208 per eye -> 258 x 276) and the magnifier (512 x 512, full size, as
views.Magnifier) into requests, in headless chromium on this machine's CPU.

The virtual texture's test page (web/vt/test/harness.html) draws the three feedback passes of
a painting on a wall every frame while the cameras walk along it at 1 m/s (VT-mobile-VR Table 2:
main camera 40 cm away, the magnifier showing 2.5 cm from 20 cm), served by `gigascroll
serve`'s application. Reported: the median over frames of (a) the processing of all three
views' last feedback together (the steady state of a headset, whose readbacks arrive every
frame), (b) beginFrame's feedback time in the loop (the readbacks' copies and processing of
whatever arrived that frame), the requests a frame, and the JS time of a frame's uploads (tiles'
texSubImage2D calls and the page table's incremental update and upload, in frames that
uploaded); the baseline in the same run is Barrett's
CPU scan, every pixel into a hash set (a JS Set), as a ratio. The pixel loop is plain JS;
SwiftShader draws the passes, which does not enter these figures."""

from __future__ import annotations

import shutil
import statistics
import tempfile
from pathlib import Path

QUEST3_EYE = (2064, 2208)
QUEST3_FOV = 96.0                      # vertical, degrees
IPD = 0.063
MAGNIFIER = (512, 512)
MAGNIFIER_FOV = 7.2                    # 2.5 cm seen from 20 cm
DISTANCE, SPEED, HZ = 0.40, 1.0, 90.0  # VT-mobile-VR Table 2
TEXEL_M = 0.25e-3
CHROMIUM_ARGS = ["--headless=new", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                 "--no-sandbox", "--enable-webgl", "--ignore-gpu-blocklist"]


def _views(height_m: float) -> list[dict]:
    """Left eye, right eye, magnifier at the painting's left quarter, 40 cm away."""
    y = 1.5 - height_m / 2
    eye = lambda dx: [0.5 + dx, y, DISTANCE, 0.5 + dx, y, 0.0, QUEST3_FOV]  # noqa: E731
    return [{"view": 0, "camera": eye(-IPD / 2), "display": list(QUEST3_EYE), "reduction": 8},
            {"view": 1, "camera": eye(IPD / 2), "display": list(QUEST3_EYE), "reduction": 8},
            {"view": 2, "camera": [0.5, y, 0.20, 0.5, y, 0.0, MAGNIFIER_FOV],
             "display": list(MAGNIFIER), "reduction": 1}]


def feedback_figures(width: int = 16000, height: int = 2000, frames: int = 240,
                     chromium: str | None = None, browser=None) -> dict:
    """Builds a pattern painting's pack (width x height, 0.25 mm texels on the wall at
    x = 0..), serves it and measures in headless chromium (a Playwright browser of the
    caller's, or the system chromium launched here); returns the figures (ms)."""
    from .. import TilePack, build_pack
    from ..experiments import pattern_image
    from ..serve import MAX_BATCH, ServerThread, make_app, pack_description, pack_hash

    if browser is None:
        chromium = chromium or shutil.which("chromium") or shutil.which("chromium-browser")
        if chromium is None:
            raise RuntimeError("chromium not found (the Makefile installs Debian's chromium)")
    w_m, h_m = width * TEXEL_M, height * TEXEL_M
    placements = [{"painting": 0, "origin": [0.0, 1.5, 0.0], "u_axis": [1, 0, 0],
                   "v_axis": [0, -1, 0], "width_m": w_m, "height_m": h_m}]
    with tempfile.TemporaryDirectory(prefix="gigascroll-bench-web-client-") as tmp:
        pack = build_pack(pattern_image(width, height), Path(tmp) / "p.pack")
        h = pack_hash(pack)
        scene = {"version": 1, "pack": pack_description(pack, h),
                 "tiles": {"batch": f"/api/tiles/{h}/batch", "max_batch": MAX_BATCH}}
        with ServerThread(make_app(TilePack(str(pack.path)), None, h)) as url:
            if browser is not None:
                r = _measure(browser, url, scene, h_m, placements, frames)
            else:
                from playwright.sync_api import sync_playwright

                with sync_playwright() as p:
                    own = p.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
                    try:
                        r = _measure(own, url, scene, h_m, placements, frames)
                    finally:
                        own.close()
    return {"painting": f"{width}x{height}", "frames": frames,
            "feedback_pixels": r["pixels"], "pixels_a_frame": sum(r["pixels"]),
            "median_ms_all_views": statistics.median(r["together"]),
            "p90_ms_all_views": sorted(r["together"])[int(0.9 * len(r["together"]))],
            "requests_all_views": r["togetherRequests"],
            "median_ms_naive_set": statistics.median(r["naive"]),
            "ratio_naive_to_ours": statistics.median(r["naive"]) / max(statistics.median(r["together"]), 1e-9),
            "median_ms_in_loop": statistics.median(r["ms"]) if r["ms"] else None,
            "median_ms_in_loop_processing": statistics.median(r["processMs"]) if r["processMs"] else None,
            "frames_with_readbacks": len(r["ms"]),
            "median_requests_in_loop": statistics.median(r["requests"]) if r["requests"] else None,
            "median_upload_ms": statistics.median(r["uploadMs"]) if r["uploadMs"] else None,
            "median_uploads": statistics.median(r["uploads"]) if r["uploads"] else None,
            "frames_with_uploads": len(r["uploads"]),
            "resident_at_end": r["stats"]["resident"], "goal_ms": 1.0}


def _measure(browser, url: str, scene: dict, h_m: float, placements, frames: int) -> dict:
    """The test page's benchFeedback on a new page of `browser`."""
    page = browser.new_page()
    try:
        page.goto(f"{url.rstrip('/')}/client/vt/test/harness.html")
        page.wait_for_function("window.vtTestReady === true")
        page.evaluate("(scene) => vtTest.init({scene})", scene)
        return page.evaluate("([v, p, n, s]) => vtTest.benchFeedback(v, p, n, s)",
                             [_views(h_m), placements, frames, [SPEED / HZ, 0, 0]])
    finally:
        page.close()


def format_figures(f: dict) -> str:
    loop = "n/a" if f["median_ms_in_loop"] is None else f"{f['median_ms_in_loop']:.3f} ms"
    return (f"feedback processing, both Quest 3 eyes at 1/8 + magnifier ({f['pixels_a_frame']} "
            f"pixels, {f['requests_all_views']} requests): median {f['median_ms_all_views']:.3f} ms, "
            f"p90 {f['p90_ms_all_views']:.3f} ms (goal <= {f['goal_ms']} ms), every pixel into a Set "
            f"{f['median_ms_naive_set']:.3f} ms ({f['ratio_naive_to_ours']:.1f}x); in the loop "
            f"(readback copies + processing of what arrived): median {loop} "
            f"over {f['frames_with_readbacks']} frames; uploads: median "
            f"{'n/a' if f['median_upload_ms'] is None else format(f['median_upload_ms'], '.3f') + ' ms'} "
            f"for {f['median_uploads']} tiles a frame")

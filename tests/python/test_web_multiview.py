"""The browser client's one-pass stereo (OVR_multiview2, web/multiview.js) and GPU frame time
(EXT_disjoint_timer_query_webgl2, web/gpu_timer.js) in headless chromium on SwiftShader, which
offers both extensions:

- both eyes drawn in one multiview pass (XR through the fake device, and the desktop's
  side-by-side stereo) equal the pass per eye (?multiview=0) pixel for pixel, within one code
  value, once the view is exact; stats() says which path drew;
- stats().gpuMs is a finite positive number, or null where the extension is missing; the
  queries are polled (a result is asked for only once its availability said yes), never waited
  on, and only a few are in flight.

SwiftShader's "GPU" time is CPU emulation: nothing here looks at its size.
"""

from pathlib import Path

import numpy as np
import pytest

from browser import browser, chromium_path  # noqa: F401 - fixtures
from test_web_app import EYE_H, EYE_W, decode, open_app, room_pack, server, wait_exact  # noqa: F401

FAKE_XR = (Path(__file__).parent / "fake_webxr.js").read_text()

# Records, per query object, whether its result was read before its availability said yes.
QUERY_SPY = """(() => {
  const get = WebGL2RenderingContext.prototype.getQueryParameter;
  window.querySpy = { available: new WeakSet(), early: 0, results: 0, checks: 0 };
  WebGL2RenderingContext.prototype.getQueryParameter = function (q, pname) {
    const v = get.call(this, q, pname), s = window.querySpy;
    if (pname === this.QUERY_RESULT_AVAILABLE) { s.checks++; if (v) s.available.add(q); }
    if (pname === this.QUERY_RESULT) { s.results++; if (!s.available.has(q)) s.early++; }
    return v;
  };
})();"""

NO_TIMER = """(() => {
  const get = WebGL2RenderingContext.prototype.getExtension;
  WebGL2RenderingContext.prototype.getExtension = function (name) {
    return name === 'EXT_disjoint_timer_query_webgl2' ? null : get.call(this, name);
  };
})();"""


def draw_eyes(browser, server, mode, multiview):  # noqa: F811
    """Both eyes of the mode ('xr' through the fake device, 'stereo' on the desktop canvas)
    once exact: (frame (H, 2W, 3), stats(), whether the context has OVR_multiview2)."""
    query = f"size={2 * EYE_W}x{EYE_H}" + ("" if multiview else "&multiview=0")
    if mode == "stereo":
        query += "&stereo=1&ipd=0.064&camera=6,1.6,-3,6,1.5,0,60"
    page = open_app(browser, server, query, init_script=FAKE_XR if mode == "xr" else None)
    gl_errors = []
    page.on("console", lambda m: "GL_INVALID" in m.text and gl_errors.append(m.text))
    try:
        if mode == "xr":
            page.wait_for_selector("#enter-vr:not([hidden])", timeout=30_000)
            page.click("#enter-vr")
            page.wait_for_function("window.gigascroll.app.xr.frames > 2")
        wait_exact(page)
        frame = decode(page.evaluate("window.gigascroll.capture()"))
        stats = page.evaluate("window.gigascroll.stats()")
        has = page.evaluate("Boolean(window.gigascroll.app.gl.getExtension('OVR_multiview2'))")
    finally:
        page.close()
    assert not gl_errors, gl_errors[:3]
    return frame, stats, has


@pytest.mark.parametrize("mode", ["xr", "stereo"])
def test_multiview_equals_pass_per_eye(browser, server, mode):  # noqa: F811
    """Both eyes in one multiview pass against a pass per eye, once exact: within one code
    value (the same shaders, the same rasteriser; a multiview layer may round a varying
    differently), drawn without a GL error, and stats() naming the path."""
    one, stats_one, has = draw_eyes(browser, server, mode, True)
    per_eye, stats_per_eye, _ = draw_eyes(browser, server, mode, False)
    assert stats_per_eye["multiview"] is False
    if not has:
        pytest.skip("this browser has no OVR_multiview2: only the pass per eye ran")
    assert stats_one["multiview"] is True, "OVR_multiview2 exists, so one pass draws both eyes"
    # A TIME_ELAPSED query may not span a multiview draw (gpu_timer.js): those frames go untimed.
    assert stats_one["gpuMs"] is None
    assert stats_per_eye["gpuMs"] is None or stats_per_eye["gpuMs"] > 0
    diff = np.abs(one.astype(int) - per_eye.astype(int))
    for k in range(2):
        eye = diff[:, k * EYE_W:(k + 1) * EYE_W]
        print(f"{mode} eye {k}: max difference {eye.max()}, {(eye > 0).any(axis=2).mean():.4%} pixels differ")
        assert eye.max() <= 1, (mode, k, int(eye.max()))
    # Not a black or uniform frame: both eyes show the room.
    assert one[:, :EYE_W].std() > 10 and one[:, EYE_W:].std() > 10


def gpu_stats(browser, server, init):  # noqa: F811
    page = open_app(browser, server, f"size={EYE_W}x{EYE_H}&camera=6,1.6,-3,6,1.5,0,60",
                    init_script=QUERY_SPY + init)
    try:
        start = page.evaluate("window.gigascroll.frame()")
        page.wait_for_function(f"window.gigascroll.frame() > {start} + 20")
        stats = page.evaluate("window.gigascroll.stats()")
        spy = page.evaluate("({early: querySpy.early, results: querySpy.results, checks: querySpy.checks})")
        pending = page.evaluate("window.gigascroll.app.timer.pending.length")
        has = page.evaluate("window.gigascroll.app.timer.ext !== null")
    finally:
        page.close()
    return stats, spy, pending, has


def test_gpu_time_polled_never_waited(browser, server):  # noqa: F811
    """A one-eye desktop page for 20 frames, its query reads spied on: no result is read
    before its availability said yes, at most 8 queries in flight, gpuMs finite and positive."""
    stats, spy, pending, has = gpu_stats(browser, server, "")
    print(f"gpuMs {stats['gpuMs']} (SwiftShader: CPU emulation), {spy}, {pending} in flight")
    assert spy["early"] == 0, "a query's result was read before it was available (a stall)"
    assert pending <= 8
    if not has:
        assert stats["gpuMs"] is None
        pytest.skip("this browser has no EXT_disjoint_timer_query_webgl2")
    assert spy["results"] > 0 and spy["checks"] > spy["results"] - 1
    assert stats["gpuMs"] is None or (np.isfinite(stats["gpuMs"]) and stats["gpuMs"] > 0)
    assert stats["gpuMs"] is not None, "20 frames gave no timer result"


def test_gpu_time_null_without_extension(browser, server):  # noqa: F811
    """A browser without the extension: no query at all, gpuMs null, the page draws on."""
    stats, spy, pending, has = gpu_stats(browser, server, NO_TIMER)
    assert not has and stats["gpuMs"] is None and spy["results"] == 0 and pending == 0


@pytest.mark.parametrize("value", ["2", "yes", "%00"])
def test_bad_multiview_parameter(browser, server, value):  # noqa: F811
    """?multiview takes 0 or 1: anything else is a one-line message on the page."""
    page = browser.new_page()
    try:
        page.goto(f"{server}/?multiview={value}")
        page.wait_for_function("window.gigascroll && window.gigascroll.error !== null", timeout=60_000)
        error = page.evaluate("window.gigascroll.error")
        assert "?multiview wants 0 or 1" in error and "\n" not in error
    finally:
        page.close()


def test_multiview_only_for_two_equal_views(browser, server):  # noqa: F811
    """multiview.js's choice: one pass only for two views of one size (an odd canvas width's
    side-by-side halves differ by a pixel: a pass per eye); a shader not written after the
    one-view HEADER is refused rather than mangled."""
    page = browser.new_page()
    try:
        page.goto(f"{server}/client/index.html?size=32x32")
        got = page.evaluate("""async () => {
          const { multiviewViews, multiviewSource } = await import('/client/multiview.js');
          const v = (x, w, h) => ({ viewport: [x, 0, w, h] });
          let refused = null;
          try { multiviewSource('void main() {}', '#version 300 es\\n', true); } catch (e) { refused = e.message; }
          const vs = multiviewSource('H\\nuniform mat4 uViewProj;\\nuniform vec3 uEye;\\n', 'H\\n', true);
          return { equal: multiviewViews([v(0, 160, 120), v(160, 160, 120)]),
                   odd: multiviewViews([v(0, 160, 120), v(160, 161, 120)]),
                   one: multiviewViews([v(0, 160, 120)]),
                   three: multiviewViews([v(0, 10, 10), v(10, 10, 10), v(20, 10, 10)]), refused, vs };
        }""")
    finally:
        page.close()
    assert got["equal"] is True and got["odd"] is False and got["one"] is False and got["three"] is False
    assert got["refused"] and "HEADER" in got["refused"]
    vs = got["vs"]
    assert "#extension GL_OVR_multiview2 : require" in vs and "layout(num_views = 2) in;" in vs
    assert "uniform mat4 uViewProjs[2];" in vs and "uniform vec3 uEyes[2];" in vs and "uniform mat4 uViewProj;" not in vs

"""The browser client's page as a visitor opens it, and URL parameters its first tests did not
try: the page loads and draws with no failed request and no console error (the browser's own
favicon request was a 404 on every visit), a ?size no canvas can have (0 pixels, or 99999 a
side, which froze the tab) and a ?camera beyond the core camera's +-1e12 m are refused with one
line, as `gigascroll render --camera` refuses them."""

from __future__ import annotations

import subprocess
import sys

import pytest

import gigascroll as g
from browser import browser, chromium_path, serve_pack  # noqa: F401 - fixtures


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    root = tmp_path_factory.mktemp("audit_web")
    g.build_pack(g.render_ink_landscape(1200, 100, 0, 100), root / "p.pack")
    with serve_pack(root / "p.pack", room="scroll", cache_dir=root / "cache") as url:
        yield url, root / "p.pack"


def test_the_page_loads_with_no_failed_request_and_no_console_error(browser, served):  # noqa: F811
    url, _ = served
    p = browser.new_page()
    failed, errors = [], []
    p.on("response", lambda r: r.status >= 400 and failed.append(f"{r.status} {r.url}"))
    p.on("requestfailed", lambda r: failed.append(f"failed {r.url}"))
    p.on("console", lambda m: m.type == "error" and errors.append(m.text))
    p.on("pageerror", lambda e: errors.append(str(e)))
    try:
        p.goto(f"{url}/?size=64x48")
        p.wait_for_function("window.gigascroll && window.gigascroll.frame() > 2", timeout=120_000)
        p.evaluate("window.gigascroll.ready()")
        assert p.evaluate("window.gigascroll.error") is None
        assert failed == [] and errors == [], (failed, errors)
    finally:
        p.close()


@pytest.mark.parametrize("query, message", [
    ("size=0x0", "?size wants"), ("size=64x0", "?size wants"),
    ("size=99999x99999", "?size wants"), ("size=8193x16", "?size wants"),
    ("camera=1e13,1.6,0,0,1.6,1", "within +-1e12"), ("camera=0,1.6,0,0,1.6,-2e12", "within +-1e12"),
])
def test_url_parameters_no_canvas_or_camera_can_have(browser, served, query, message):  # noqa: F811
    url, _ = served
    p = browser.new_page()
    try:
        p.goto(f"{url}/?{query}")
        p.wait_for_function("window.gigascroll && window.gigascroll.error !== null", timeout=60_000)
        error = p.evaluate("window.gigascroll.error")
        assert message in error and "\n" not in error, error
    finally:
        p.close()


def test_render_refuses_the_camera_the_page_refuses(served, tmp_path):
    """The same ?camera value is an error for `render --camera` (the convention it follows)."""
    _, pack = served
    r = subprocess.run([sys.executable, "-m", "gigascroll", "render", "--room", "scroll", "--pack",
                        str(pack), "--camera", "1e13,1.6,0,0,1.6,1", "-o", str(tmp_path / "c.png"),
                        "--width", "8", "--height", "8", "--lighting", "unlit"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "1e12" in r.stderr and not (tmp_path / "c.png").exists(), r.stderr


def test_the_readme_camera_looks_at_the_painting_from_inside_the_room(served):
    """The README's ?camera example stands inside the scroll room and looks at the painting's
    front (it stood behind the wall: a black page)."""
    import json
    import re
    import urllib.request
    from pathlib import Path

    import numpy as np
    url, _ = served
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    found = re.findall(r"\?camera=([-0-9.,]+)", readme)
    assert found, "the README shows a ?camera example"
    with urllib.request.urlopen(url + "/api/scene.json") as r:
        room = json.load(r)["room"]
    lo, hi = np.array(room["bounds"])
    slot = room["slots"][0]
    origin, u, v = (np.array(slot[k], float) for k in ("origin", "u_axis", "v_axis"))
    normal = np.cross(u, v)
    for text in found:
        x = [float(t) for t in text.split(",")]
        eye, target = np.array(x[:3]), np.array(x[3:6])
        assert np.all(lo < eye) and np.all(eye < hi), (text, room["bounds"])
        d = target - eye
        t = (origin - eye) @ normal / (d @ normal)   # where the gaze meets the painting's plane
        hit = eye + t * d - origin
        assert t > 0 and 0 <= hit @ u <= slot["width_m"] and 0 <= hit @ v <= slot["height_m"], text


FETCH_BATCH = """async ([url, keys, tileBytes]) => {
  const { fetchBatch, retryAfterMs } = await import('/client/vt/fetch_batch.js');
  const waits = [];
  const r = await fetchBatch({ id: 1, url, keys, indices: keys.map((_, i) => i), tileBytes },
                             async (ms) => { waits.push(ms); });
  const sum = (b) => new Uint8Array(b).reduce((s, x) => s + x, 0);
  return { error: r.error ?? null, sums: r.tiles ? r.tiles.map((t) => sum(t.bytes)) : null, waits,
           parsed: [retryAfterMs('2', 1), retryAfterMs(null, 1), retryAfterMs(null, 3),
                    retryAfterMs('999', 1), retryAfterMs('x', 2)] };
}"""


@pytest.mark.parametrize("busy", [2, 99])
def test_a_busy_server_is_asked_again(browser, served, busy):  # noqa: F811
    """The client's batch fetch answers the server's 429 (every tile slot busy) by asking
    again after Retry-After: two 429s and then the tiles give the tiles (the coarse tail a
    page waits for was a failed page); a server busy for ever gives up after MAX_TRIES."""
    import numpy as np
    url, pack_path = served
    from gigascroll import TilePack
    from gigascroll.serve import pack_hash
    pack = TilePack(str(pack_path))
    keys = [[0, pack.paintings[0].levels - 1, 0, 0], [0, 0, 0, 0]]
    batch = f"/api/tiles/{pack_hash(pack)}/batch"
    p = browser.new_page()
    answered = []

    def route(r):
        answered.append(r.request.url)
        if len(answered) <= busy:
            r.fulfill(status=429, headers={"Retry-After": "1"}, body="busy\n")
        else:
            r.continue_()
    try:
        p.goto(f"{url}/api/scene.json")  # a page of the origin: the module imports alone
        p.route(f"**{batch}", route)
        got = p.evaluate(FETCH_BATCH, [batch, keys, 128 * 128 * 3])
    finally:
        p.close()
    assert got["parsed"] == [2000, 250, 1000, 5000, 500]
    if busy == 2:
        assert got["error"] is None and len(answered) == 3 and got["waits"] == [1000, 1000]
        assert got["sums"] == [int(pack.read_tile(*k).astype(np.int64).sum()) for k in keys]
    else:
        assert "HTTP 429" in got["error"] and len(answered) == 6 and len(got["waits"]) == 5

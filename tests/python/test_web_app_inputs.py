"""The browser client's inputs (python/gigascroll/web/): the room glb reader (glb.js) against the
served file read with numpy, and refusals of damaged glbs and bad URL parameters with a clear
one-line message rather than a hang, a crash or a wrong picture."""

import json
import struct

import numpy as np
import pytest

import gigascroll as g
from browser import browser, chromium_path, serve_pack  # noqa: F401 - fixtures

READ_GLB = """async ([url, cut, patch]) => {
  const { parseRoom } = await import('/client/glb.js');
  let buf = await (await fetch(url)).arrayBuffer();
  if (cut !== null) buf = buf.slice(0, cut);
  if (patch !== null) { const b = new Uint8Array(buf); b.set(patch[1], patch[0]); }
  try {
    const meshes = parseRoom(buf);
    const sum = (a) => a ? Array.from(a).reduce((s, x) => s + x, 0) : null;
    return meshes.map((m) => ({ name: m.name, vertices: m.vertexCount, indices: m.indices?.length ?? null,
      front: sum(m.irradianceFront), back: sum(m.irradianceBack), uv: sum(m.texcoords),
      painting: m.painting, slot: m.slot, albedo: m.albedo, emission: m.emission }));
  } catch (e) { return { error: String(e.message) }; }
}"""


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    img = g.render_ink_landscape(3000, 120, 0, 120)
    path = tmp_path_factory.mktemp("web_inputs") / "p.pack"
    g.build_pack(img, path)
    with serve_pack(path, room="scroll", cache_dir=tmp_path_factory.mktemp("cache")) as url:
        yield url


@pytest.fixture(scope="module")
def page(browser, served):  # noqa: F811
    p = browser.new_page()
    p.goto(f"{served}/client/index.html?size=32x32")  # any page of the origin: glb.js imports alone
    yield p
    p.close()


def numpy_room(url):
    """The glb's meshes summed with numpy from its JSON and binary chunks."""
    import urllib.request

    with urllib.request.urlopen(url) as r:
        data = r.read()
    n_json = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + n_json])
    bin_start = 20 + n_json + 8
    out = []
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            def arr(i, dtype=np.float32):
                acc = doc["accessors"][i]
                view = doc["bufferViews"][acc["bufferView"]]
                k = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[acc["type"]]
                start = bin_start + view.get("byteOffset", 0) + acc.get("byteOffset", 0)
                dt = {5126: np.float32, 5125: np.uint32, 5123: np.uint16}[acc["componentType"]]
                return np.frombuffer(data, dt, acc["count"] * k, start)
            a = prim["attributes"]
            out.append({"vertices": len(arr(a["POSITION"])) // 3,
                        "front": float(arr(a["_IRRADIANCE_FRONT"]).astype(np.float64).sum()),
                        "back": float(arr(a["_IRRADIANCE_BACK"]).astype(np.float64).sum()),
                        "uv": float(arr(a["TEXCOORD_0"]).astype(np.float64).sum()) if "TEXCOORD_0" in a else None,
                        "indices": len(arr(prim["indices"])) if "indices" in prim else None})
    return out, data, doc


def test_glb_reader_equals_numpy(page, served):
    scene = page.evaluate("async () => (await fetch('/api/scene.json')).json()")
    url = served + scene["room"]["glb"]
    ours = page.evaluate(READ_GLB, [scene["room"]["glb"], None, None])
    theirs, _, _ = numpy_room(url)
    assert len(ours) == len(theirs) and sum(m["painting"] >= 0 for m in ours) == len(scene["room"]["slots"])
    for a, b in zip(ours, theirs):
        assert a["vertices"] == b["vertices"] and a["indices"] == b["indices"]
        for k in ("front", "back"):
            assert a[k] == pytest.approx(b[k], rel=1e-9)
        assert (a["uv"] is None) == (b["uv"] is None) and (a["uv"] is None or a["uv"] == pytest.approx(b["uv"], rel=1e-9))
        assert (a["painting"] >= 0) == (a["uv"] is not None)
    assert any(max(m["emission"]) > 0 for m in ours), "the room's lights carry their emission"


def test_damaged_glbs_refused(page, served):
    scene = page.evaluate("async () => (await fetch('/api/scene.json')).json()")
    path = scene["room"]["glb"]
    _, data, doc = numpy_room(served + path)
    n_json = struct.unpack_from("<I", data, 12)[0]
    cases = {
        "truncated": (len(data) // 2, None),
        "header only": (12, None),
        "bad magic": (None, [0, [0, 0, 0, 0]]),
        "version 1": (None, [4, [1, 0, 0, 0]]),
        "json chunk past the end": (None, [12, list(struct.pack("<I", len(data) * 2))]),
    }
    # An accessor past its buffer view: the JSON rewritten with the first view cut to 4 bytes.
    bad = json.loads(data[20:20 + n_json])
    bad["bufferViews"][bad["accessors"][0]["bufferView"]]["byteLength"] = 4
    text = json.dumps(bad, separators=(",", ":")).encode()
    assert len(text) <= n_json
    cases["accessor past its view"] = (None, [20, list(text.ljust(n_json))])
    for what, (cut, patch) in cases.items():
        r = page.evaluate(READ_GLB, [path, cut, patch])
        assert isinstance(r, dict) and r["error"].startswith("room glb:"), (what, r)
        assert "\n" not in r["error"], what


@pytest.mark.parametrize("query, message", [
    ("camera=nan,1,2,3,4,5", "?camera wants"),
    ("camera=1,2,3", "?camera wants"),
    ("camera=0,1,0,0,1,0", "eye and target must differ"),
    ("camera=0,1,0,0,1,1,180", "field of view"),
    ("camera=0,1,0,0,1,1,1e400", "?camera wants"),
    ("size=10", "?size wants"),
    ("ipd=-1", "?ipd wants"),
])
def test_bad_url_parameters(browser, served, query, message):  # noqa: F811
    p = browser.new_page()
    try:
        p.goto(f"{served}/?{query}")
        p.wait_for_function("window.gigascroll && window.gigascroll.error !== null", timeout=60_000)
        error = p.evaluate("window.gigascroll.error")
        assert message in error and "\n" not in error
        assert p.evaluate("document.getElementById('error').hidden") is False
    finally:
        p.close()


def test_desktop_walking(browser, served):  # noqa: F811
    """WASD walks along the view's horizontal forward and right, Q lowers the eye, dragging to
    the right turns right, and walking never leaves the room's bounds (directions only: no
    timing is asserted)."""
    p = browser.new_page(viewport={"width": 160, "height": 120})
    try:
        p.goto(f"{served}/?size=160x120")
        p.wait_for_function("window.gigascroll && window.gigascroll.frame() > 0", timeout=120_000)
        state = "(() => { const c = window.gigascroll.app.controls; return [...c.position, c.yaw]; })()"
        bounds = p.evaluate("window.gigascroll.app.scene.room.bounds")
        start = p.evaluate(state)
        forward = np.array([-np.sin(start[3]), 0, -np.cos(start[3])])
        right = np.array([np.cos(start[3]), 0, -np.sin(start[3])])

        def hold(key, ms=400):
            before = np.array(p.evaluate(state))
            p.keyboard.down(key)
            p.wait_for_timeout(ms)
            p.keyboard.up(key)
            p.wait_for_function(f"window.gigascroll.frame() > {p.evaluate('window.gigascroll.frame()')} + 1")
            return np.array(p.evaluate(state)) - before

        for key, direction in (("KeyW", forward), ("KeyD", right), ("KeyS", -forward), ("KeyA", -right)):
            d = hold(key)[:3]
            assert d @ direction > 0.01 and np.linalg.norm(d - (d @ direction) * direction) < 1e-6, (key, d)
        d = hold("KeyQ")
        assert d[1] < -0.01 and abs(d[0]) + abs(d[2]) < 1e-6
        box = p.evaluate("document.getElementById('view').getBoundingClientRect().toJSON()")
        p.mouse.move(box["x"] + 40, box["y"] + 60)
        p.mouse.down()
        p.mouse.move(box["x"] + 120, box["y"] + 60, steps=4)
        p.mouse.up()
        assert p.evaluate(state)[3] < start[3] - 0.1  # yaw down: turned right
        hold("ShiftLeft", 0)
        p.keyboard.down("ShiftLeft")
        hold("KeyS", 3000)  # backwards toward a wall: stopped at the margin
        p.keyboard.up("ShiftLeft")
        pos = p.evaluate(state)[:3]
        assert all(bounds[0][i] + 0.1 < pos[i] < bounds[1][i] - 0.1 for i in range(3)), (pos, bounds)
    finally:
        p.close()

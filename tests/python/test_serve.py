"""`gigascroll serve` against the core: every tile's bytes equal `TilePack.read_tile`'s, the
scene describes the pack and room as the core holds them, bad requests get a 4xx and one log
line, and the command starts, announces its URL and stops as promised. The glb's check
against the core's irradiance is in test_serve_glb.py, the many-client soak in
test_serve_soak.py."""

from __future__ import annotations

import json
import os
import signal
import socket
import urllib.error
import urllib.request

import numpy as np
import pytest
from serve_support import ServeProcess, client_context, get_request, raw_request, self_signed

import gigascroll
from gigascroll import build_pack
from gigascroll.experiments import pattern_image
from gigascroll.gallery.exposure import room_display
from gigascroll.serve import MAX_BATCH, ServerThread, baked_room, make_app, pack_hash


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """(pack, room, url) of an in-process server of a 2000 x 300 pack in the scroll room."""
    root = tmp_path_factory.mktemp("serve")
    pack = build_pack(pattern_image(2000, 300), root / "p.pack")
    h = pack_hash(pack)
    room = baked_room("scroll", pack, h, cache_dir=root / "cache")
    with ServerThread(make_app(pack, room, h)) as url:
        yield pack, room, url.rstrip("/")


def fetch(url, data=None, method=None, headers=None):
    """(status, headers, body) without raising on 4xx."""
    req = urllib.request.Request(url, data=data, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def all_keys(pack):
    return [(p, level, x, y) for p, pt in enumerate(pack.paintings)
            for level, (nx, ny) in enumerate(pt.level_tiles) for x in range(nx) for y in range(ny)
            if pack.has_tile(p, level, x, y)]


def test_every_tile_equals_the_core(served):
    pack, _, url = served
    h = pack_hash(pack)
    keys = all_keys(pack)
    assert len(keys) == 80
    for key in keys:
        status, headers, body = fetch(f"{url}/api/tiles/{h}/{key[0]}/{key[1]}/{key[2]}/{key[3]}")
        assert status == 200
        assert body == pack.read_tile(*key).tobytes()
        assert headers["Cache-Control"] == "public, max-age=31536000, immutable"
        assert h in headers["ETag"]
    # The ETag answers a revalidation without the bytes.
    status, _, body = fetch(f"{url}/api/tiles/{h}/0/0/0/0", headers={"If-None-Match": headers["ETag"]})
    assert (status, body) == (304, b"") or key != (0, 0, 0, 0) and status == 200


def test_batch_is_the_tiles_in_the_order_asked(served, rng):
    pack, _, url = served
    h = pack_hash(pack)
    keys = all_keys(pack)
    for n in (1, 7, MAX_BATCH):
        chosen = [keys[i] for i in rng.integers(0, len(keys), n)]  # repeats allowed
        status, headers, body = fetch(f"{url}/api/tiles/{h}/batch",
                                      data=json.dumps({"keys": chosen}).encode(), method="POST")
        assert status == 200 and headers["Content-Type"] == "application/octet-stream"
        assert body == b"".join(pack.read_tile(*k).tobytes() for k in chosen)


@pytest.mark.parametrize("path, status", [
    ("/api/tiles/{h}/0/0/99/0", 404), ("/api/tiles/{h}/0/9/0/0", 404), ("/api/tiles/{h}/1/0/0/0", 404),
    ("/api/tiles/{h}/0/0/31/3", 404),           # inside the page-table grid: a padding tile
    ("/api/tiles/{other}/0/0/0/0", 404), ("/api/tiles/{h}/0/0/-1/0", 400),
    ("/api/tiles/{h}/0/0/1e3/0", 400), ("/api/tiles/{h}/0/0/0x1/0", 400),
    ("/api/tiles/{h}/0/0/99999999999999999999/0", 400), ("/api/room/nope.glb", 404),
    ("/nothing", 404), ("/api/tiles/{h}", 404),
])
def test_bad_tile_urls_are_4xx(served, path, status):
    pack, _, url = served
    h = pack_hash(pack)
    got, headers, body = fetch(url + path.format(h=h, other="0" * 32))
    assert got == status
    assert headers["Content-Type"].startswith("text/plain") and body.count(b"\n") == 1


@pytest.mark.parametrize("body, status", [
    (b"", 400), (b"{", 400), (b"[]", 400), (b'{"keys": 3}', 400), (b'{"keys": [[0, 0, 0]]}', 400),
    (b'{"keys": [[0, 0, 0, -1]]}', 400), (b'{"keys": [[0, 0, 0, 1.5]]}', 400),
    (b'{"keys": [[0, 0, 0, true]]}', 400), (b'{"keys": [[0, 0, 0, "1"]]}', 400),
    (b'{"keys": [[0, 0, 0, 99]]}', 404), (json.dumps({"keys": [[0, 0, 0, 0]] * 65}).encode(), 413),
    (b" " * (64 * 1024 + 1), 413), (b"[" * 30000 + b"]" * 30000, 400),
])
def test_bad_batches_are_4xx(served, body, status):
    pack, _, url = served
    got, _, text = fetch(f"{url}/api/tiles/{pack_hash(pack)}/batch", data=body, method="POST")
    assert got == status, text


def test_wrong_methods_are_405(served):
    pack, room, url = served
    h = pack_hash(pack)
    assert fetch(f"{url}/api/tiles/{h}/batch")[0] == 405
    assert fetch(f"{url}/api/scene.json", data=b"x", method="POST")[0] == 405
    assert fetch(f"{url}/api/tiles/{h}/0/0/0/0", method="DELETE")[0] == 405


def test_scene_describes_the_pack_and_room(served):
    pack, room, url = served
    status, headers, body = fetch(url + "/api/scene.json")
    scene = json.loads(body)
    h = pack_hash(pack)
    p = scene["pack"]
    assert p["hash"] == h and (p["tile_size"], p["border"], p["payload"]) == (128, 4, 120)
    assert tuple(p["table_size"]) == pack.table_size
    q, core = p["paintings"][0], pack.paintings[0]
    assert (q["width"], q["height"], q["levels"]) == (core.width, core.height, core.levels)
    assert [tuple(s) for s in q["level_tiles"]] == list(core.level_tiles)
    assert tuple(q["table_offset"]) == core.table_offset and tuple(q["uv_scale"]) == core.uv_scale
    r = scene["room"]
    assert r["name"] == "scroll" and r["glb"] == f"/api/room/{room.key}.glb"
    slot = room.spec.paintings[0]
    assert r["slots"][0]["width_m"] == slot.width_m and r["slots"][0]["painting"] == 0
    assert r["camera"]["eye"] == list(room.spec.camera_eye) and r["camera"]["fov"] == 60.0
    assert np.allclose(r["bounds"], room.gallery.bounds)
    # the room's automatic exposure (gallery/exposure.py) and the neutral curve
    assert scene["display"] == room_display(room.spec).scene_json()
    assert scene["display"]["tone"] == "neutral-srgb" and 5 < scene["display"]["ev100"] < 7
    assert scene["tiles"]["batch"] == f"/api/tiles/{h}/batch" and scene["tiles"]["max_batch"] == 64
    status, headers, glb = fetch(url + r["glb"])
    assert status == 200 and glb == room.glb_path.read_bytes() and glb[:4] == b"glTF"
    assert headers["Cache-Control"] == "public, max-age=31536000, immutable"


def test_the_pack_hash_follows_the_content(tmp_path):
    a = build_pack(pattern_image(300, 200), tmp_path / "a")
    b = build_pack(pattern_image(300, 200), tmp_path / "b")
    img = pattern_image(300, 200)
    img[5, 5] ^= 1
    c = build_pack(img, tmp_path / "c")
    assert pack_hash(a) == pack_hash(b) != pack_hash(c)


def test_client_files_stay_inside_their_folder(tmp_path, served):
    pack, _, _ = served
    client = tmp_path / "web"
    (client / "vt").mkdir(parents=True)
    (client / "index.html").write_text("<p>index</p>")
    (client / "vt" / "a.js").write_text("export const a = 1;")
    (client / ".hidden.js").write_text("secret")
    (client / "notes.txt").write_text("not a client file")
    (tmp_path / "outside.js").write_text("outside")
    (client / "out.js").symlink_to(tmp_path / "outside.js")
    (client / "in.js").symlink_to(client / "vt" / "a.js")
    with ServerThread(make_app(pack, None, client_dir=client)) as url:
        url = url.rstrip("/")
        assert fetch(url + "/")[2] == b"<p>index</p>"
        status, headers, body = fetch(url + "/client/vt/a.js")
        assert status == 200 and body == b"export const a = 1;"
        assert headers["Content-Type"].startswith("text/javascript")
        assert fetch(url + "/client/in.js")[2] == b"export const a = 1;"
        for path in [b"/client/out.js", b"/client/.hidden.js", b"/client/notes.txt",
                     b"/client/vt/", b"/client/vt", b"/client/", b"/client/vt/../../outside.js",
                     b"/client/%2e%2e/outside.js", b"/client/vt/%2e%2e/%2e%2e/outside.js",
                     b"/client/..%2foutside.js", b"/client/vt%2f..%2f..%2foutside.js",
                     b"/client/%2Fetc%2Fpasswd", b"/client//etc/passwd", b"/client/a%00.js",
                     b"/client/vt\\..\\..\\outside.js", b"/client/" + str(tmp_path).encode() + b"/outside.js",
                     b"/../outside.js", b"/client/vt/a.js%00", b"/%2e%2e/%2e%2e/etc/passwd",
                     b"http://x/client/../../outside.js", b"/client/" + b"a/" * 400 + b"a.js",
                     b"/client/\xff\xfe.js", b"/api/scene.json/../../outside.js"]:
            status, data = raw_request(url, get_request(path))
            assert status is not None and 400 <= status < 500, (path, data[:200])
            assert b"outside" not in data.split(b"\r\n\r\n", 1)[-1], path


def start(args, tmp_path, **kw):
    return ServeProcess(args, tmp_path, **kw)


def test_cli_serves_and_stops_on_sigint_and_sigterm(tmp_path, served):
    pack, _, _ = served
    args = [pack.path, "--room", "scroll", "--port", "0", "--cache-dir", tmp_path / "cache"]
    first = start(args, tmp_path)
    assert first.url.startswith("http://127.0.0.1:")
    scene = json.loads(fetch(first.url + "/api/scene.json")[2])
    assert first.stop(signal.SIGINT) == 0
    err = first.stderr()
    assert "cache miss" in err and "stopped (SIGINT)" in err.splitlines()[-1]
    assert "Traceback" not in err
    second = start(args, tmp_path)       # the same room, pack and lighting: no bake
    assert json.loads(fetch(second.url + "/api/scene.json")[2]) == scene
    assert second.stop(signal.SIGTERM) == 0
    err = second.stderr()
    assert "bake cache hit" in err and "baking" not in err and "cache miss" not in err
    assert err.splitlines()[-1].endswith("stopped (SIGTERM)")
    assert len(list((tmp_path / "cache").iterdir())) == 1     # no temporaries left


def _one_error_line(proc) -> str:
    code = proc.stop()
    lines = [ln for ln in proc.stderr().splitlines() if ln.strip()]
    assert code == 2 and proc.url is None, lines
    assert len(lines) == 1 and ": error:" in lines[0] and "Traceback" not in lines[0], lines
    return lines[0]


def test_cli_port_in_use_and_bad_tls_are_one_line(tmp_path, served):
    pack, room, _ = served
    base = [pack.path, "--room", "scroll", "--cache-dir", room.glb_path.parent]
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert "cannot listen" in _one_error_line(start(base + ["--port", port], tmp_path))
    (tmp_path / "junk.pem").write_text("not a certificate")
    cert, key = self_signed(tmp_path)
    for tls in (["--tls-cert", tmp_path / "missing.pem", "--tls-key", key],
                ["--tls-cert", tmp_path / "junk.pem", "--tls-key", key],
                ["--tls-cert", cert, "--tls-key", cert], ["--tls-cert", key, "--tls-key", key],
                ["--tls-cert", cert]):
        assert "TLS" in _one_error_line(start(base + ["--port", "0", *tls], tmp_path))


def test_tls_is_served_and_fetched(tmp_path, served):
    pack, room, _ = served
    cert, key = self_signed(tmp_path)
    proc = start([pack.path, "--room", "scroll", "--port", "0", "--cache-dir", room.glb_path.parent,
                  "--tls-cert", cert, "--tls-key", key], tmp_path)
    try:
        assert proc.url.startswith("https://127.0.0.1:")
        ctx = client_context(cert)
        with urllib.request.urlopen(proc.url + "/api/scene.json", context=ctx, timeout=30) as r:
            h = json.load(r)["pack"]["hash"]
        with urllib.request.urlopen(f"{proc.url}/api/tiles/{h}/0/1/2/1", context=ctx, timeout=30) as r:
            assert r.read() == pack.read_tile(0, 1, 2, 1).tobytes()
        with pytest.raises(urllib.error.URLError):  # the certificate is checked: not a CA we trust
            urllib.request.urlopen(proc.url + "/api/scene.json", timeout=30)
    finally:
        assert proc.stop() == 0


def test_plain_http_off_localhost_warns(tmp_path, served):
    pack, room, _ = served
    proc = start([pack.path, "--room", "scroll", "--host", "0.0.0.0", "--port", "0",
                  "--cache-dir", room.glb_path.parent], tmp_path)
    assert proc.stop() == 0
    warnings = [ln for ln in proc.stderr().splitlines() if "warning" in ln]
    assert len(warnings) == 1 and "HTTPS" in warnings[0]


def test_bad_requests_log_one_line_each(tmp_path, served):
    pack, room, _ = served
    proc = start([pack.path, "--room", "scroll", "--port", "0", "--cache-dir", room.glb_path.parent],
                 tmp_path)
    try:
        before = len(proc.stderr().splitlines())
        bad = [get_request(b"/client/%2e%2e/serve/app.py"), get_request(b"/api/tiles/x/0/0/0/0"),
               get_request(b"/api/tiles/x/batch", b"POST", b"{"), b"GARBAGE\r\n\r\n",
               get_request(b"/api/scene.json", b"PUT"), b"GET /\x00 HTTP/1.1\r\n\r\n",
               get_request(b"/", headers=b"Content-Length: -5\r\n")]
        for request in bad:
            status, _ = raw_request(proc.url, request)
            assert status is not None and 400 <= status < 500, request
        fetch(proc.url + "/api/scene.json")
    finally:
        assert proc.stop() == 0
    lines = proc.stderr().splitlines()[before:]
    assert "Traceback" not in "\n".join(lines)
    assert len(lines) == len(bad) + 1, lines       # one per bad request, and "stopped"


def test_os_environment_cache_default(tmp_path, monkeypatch):
    from gigascroll.serve import default_cache_dir
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert default_cache_dir() == tmp_path / "gigascroll" / "rooms"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_cache_dir() == tmp_path / "home" / ".cache" / "gigascroll" / "rooms"
    assert os.path.basename(gigascroll.__file__)

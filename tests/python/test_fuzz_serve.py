"""Fuzz `gigascroll serve`: random options (each case in a forked child that stops itself with
SIGTERM once it serves: exit 0, or 2 with one error line, never a traceback or a hang), and
random requests to a running server (random methods, paths, bodies and headers as raw bytes:
always an answer, never a 5xx, never a traceback in its log)."""

from __future__ import annotations

import os
import re
import string

import pytest
from fuzz_support import (CASES, cli_message_ok, count_case, fork_worker, fuzz_settings,  # noqa: F401
                          long_only)
from hypothesis import given
from hypothesis import strategies as st
from serve_support import ServeProcess, get_request, raw_request, scene_of, self_signed

from gigascroll import build_pack
from gigascroll.experiments import pattern_image

# A case's code: serve_forever sends its own process SIGTERM once the URL is announced.
CASE = '''
import os, signal, threading
import gigascroll.serve as serve
run = serve.serve_forever
def stopping(*args, announce=print, **kw):
    def say(url):
        announce(url)
        threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)).start()
    return run(*args, announce=say, **kw)
serve.serve_forever = stopping
from gigascroll import cli
raise SystemExit(cli.main({argv!r}))
'''


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz-serve")
    build_pack(pattern_image(300, 120), d / "pack", tile_size=32, border=2)
    cert, key = self_signed(d)
    (d / "junk.pem").write_text("-----BEGIN CERTIFICATE-----\nnot base64\n")
    (d / "garbage.glb").write_bytes(b"glTF" + bytes(range(256)) * 4)
    (d / "empty").mkdir()
    (d / "manifest-dir" / "manifest.json").mkdir(parents=True)
    (d / "cache").mkdir()
    os.mkfifo(d / "fifo.pem")
    return {k: str(v) for k, v in dict(pack=d / "pack", cert=cert, key=key, junk=d / "junk.pem",
                                        fifo=d / "fifo.pem",
                                        glb=d / "garbage.glb", empty=d / "empty",
                                        manifest_dir=d / "manifest-dir", cache=d / "cache",
                                        missing=d / "missing", dir=d).items()}


@st.composite
def serve_argv(draw, f):
    pack = draw(st.sampled_from([f["pack"]] * 4 + [f["missing"], f["glb"], f["empty"],
                                                    f["manifest_dir"], ""]))
    room = draw(st.sampled_from(["scroll"] * 4 + ["hall", f["glb"], f["missing"] + ".glb",
                                                  f["empty"], "", "SCROLL", "../../x.obj"]))
    argv = ["serve", pack, "--room", room]
    if draw(st.booleans()):
        argv += ["--port", draw(st.sampled_from(["0"] * 3 + ["-1", "65536", "x", "", "1e3",
                                                              "99999999999999999999"]))]
    else:
        argv += ["--port", "0"]
    if draw(st.booleans()):
        argv += ["--host", draw(st.sampled_from(["127.0.0.1", "::1", "localhost", "0.0.0.0",
                                                 "256.0.0.1", "no-such-host.invalid", "",
                                                 "\U0001f4a5", "a" * 300, "127.0.0.1:80"]))]
    tls = draw(st.sampled_from([[], [], ["--tls-cert", f["cert"], "--tls-key", f["key"]],
                                ["--tls-cert", f["cert"]], ["--tls-key", f["key"]],
                                ["--tls-cert", f["junk"], "--tls-key", f["key"]],
                                ["--tls-cert", f["key"], "--tls-key", f["cert"]],
                                ["--tls-cert", f["missing"], "--tls-key", f["missing"]],
                                ["--tls-cert", f["dir"], "--tls-key", f["key"]],
                                ["--tls-cert", f["fifo"], "--tls-key", f["key"]],
                                ["--tls-cert", f["cert"], "--tls-key", f["fifo"]],
                                ["--tls-cert", "/dev/zero", "--tls-key", "/dev/zero"]]))
    cache = draw(st.sampled_from([f["cache"]] * 4 + [f["glb"], f["missing"] + "/a/b", "",
                                                     "/proc/no/such", f["pack"] + "/index.bin"]))
    threads = draw(st.sampled_from([[], ["--threads", "1"], ["--threads", "-3"]]))
    return argv + tls + ["--cache-dir", cache] + threads


def _run_cli_case(fork_worker, files, data, family):
    argv = data.draw(serve_argv(files))
    count_case(family)
    o = fork_worker.run({"kind": "python", "code": CASE.format(argv=argv), "cwd": files["dir"]},
                        timeout=90)
    problem = cli_message_ok(o)
    assert problem is None, f"gigascroll {argv!r}: {problem}\n{o.describe()}"
    if o.code == 0:
        assert o.stdout.startswith("serving http") and "stopped (SIGTERM)" in o.stderr, o.describe()


@fuzz_settings(15)
@given(data=st.data())
def test_fuzz_serve_options(fork_worker, files, data):
    _run_cli_case(fork_worker, files, data, "serve-cli")


@pytest.mark.fuzz
@long_only
@fuzz_settings(30, long_examples=600, long=True)
@given(data=st.data())
def test_fuzz_serve_options_long(fork_worker, files, data):
    _run_cli_case(fork_worker, files, data, "serve-cli-long")


# ----------------------------------------------------------------------------- requests

@pytest.fixture(scope="module")
def server(files, tmp_path_factory):
    proc = ServeProcess([files["pack"], "--room", "scroll", "--port", "0", "--cache-dir",
                         files["cache"]], tmp_path_factory.mktemp("fuzz-serve-log"))
    scene = scene_of(proc.url)
    yield proc, scene
    code = proc.stop()
    log = proc.stderr()
    assert code == 0 and "Traceback" not in log, log[-3000:]
    assert not re.search(r"serve: 5\d\d ", log), log[-3000:]


SAFE = (string.ascii_letters + string.digits + "-._~%/?&=+!$'()*,;:@[]{}|^`\\\"<>#").encode()


def _segments(scene):
    h = scene["pack"]["hash"]
    words = ["api", "tiles", "client", "room", "batch", "scene.json", h, h[:-1] + "0", "0", "1",
             "2", "-1", "..", "%2e%2e", "%2E%2e", ".", "", "index.html", "vt", "main.js",
             "%00", "%2f", "\\", "9" * 30, "1e3", "0x1", "%ff", "..%2f..%2f", "/etc/passwd",
             scene["room"]["glb"].rsplit("/", 1)[1]]
    return st.one_of(st.sampled_from(words), st.binary(max_size=12).map(
        lambda b: "".join(chr(c) if c in SAFE else f"%{c:02X}" for c in b)))


@st.composite
def request_bytes(draw, scene):
    method = draw(st.sampled_from([b"GET"] * 4 + [b"POST"] * 3 + [
        b"HEAD", b"PUT", b"DELETE", b"OPTIONS", b"PATCH", b"TRACE", b"get", b"GE\x00T", b"X" * 70]))
    parts = draw(st.lists(_segments(scene), max_size=8))
    path = ("/" + "/".join(parts)).encode()
    if draw(st.integers(0, 5)) == 0:
        path = draw(st.sampled_from([b"*", b"http://x/api/scene.json", b"//", b"/" * 300,
                                     b"/api/tiles/" + scene["pack"]["hash"].encode() + b"/batch"]))
    body = draw(st.one_of(
        st.binary(max_size=300),
        st.lists(st.lists(st.integers(-2, 40), max_size=5), max_size=70).map(
            lambda ks: ('{"keys": %s}' % ks).encode()),
        st.sampled_from([b"", b"{}", b'{"keys": []}', b"null", b"[" * 5000, b"\xff\xfe"])))
    headers = draw(st.sampled_from([b"", b"Content-Type: application/json\r\n",
                                    b"Transfer-Encoding: chunked\r\n", b"Expect: 100-continue\r\n",
                                    b"If-None-Match: *\r\n", b"Range: bytes=5-1\r\n",
                                    b"Accept-Encoding: gzip\r\n", b"X: \xff\r\n"]))
    return get_request(path, method, body, headers)


def _run_request_case(server, data, family):
    proc, scene = server
    request = data.draw(request_bytes(scene))
    count_case(family)
    status, response = raw_request(proc.url, request, timeout=30)
    assert proc.proc.poll() is None, "the server died"
    assert status is not None and 100 <= status < 500, (request[:300], response[:300])


@fuzz_settings(150)
@given(data=st.data())
def test_fuzz_serve_requests(server, data):
    _run_request_case(server, data, "serve-requests")


@pytest.mark.fuzz
@long_only
@fuzz_settings(150, long_examples=5000, long=True)
@given(data=st.data())
def test_fuzz_serve_requests_long(server, data):
    _run_request_case(server, data, "serve-requests-long")


# ----------------------------------------------------------------------------- Python API

API = ["pack_hash", "pack_description", "room_key", "baked_room", "make_app", "scene_document",
       "tls_context", "default_cache_dir"]
VALUES = ["0", "-1", "2**64", "None", "True", "float('nan')", "''", "'x'", "'scroll'", "'hall'",
          "'\\udcff'", "'a' * 5000", "b'x'", "[]", "{}", "{'photons': 1}", "PACK", "PACK_PATH",
          "CERT", "KEY", "JUNK", "CACHE", "'/nonexistent/x'", "SPEC", "HASH", "ROOM", "object()"]
API_CASE = '''
import gigascroll, gigascroll.serve as serve
from gigascroll.gallery import builtin_room
PACK_PATH, CERT, KEY, JUNK, CACHE = {paths!r}
PACK = gigascroll.TilePack(PACK_PATH)
HASH = serve.pack_hash(PACK)
SPEC = builtin_room("scroll", PACK)
ROOM = serve.baked_room("scroll", PACK, HASH, CACHE) if {needs_room!r} else None
try:
    result = getattr(serve, {name!r})({args})
    if {name!r} == "make_app":
        result[serve.app.STATE_KEY].pool.shutdown()
except (ValueError, OSError, TypeError) as e:
    print(type(e).__name__, " ".join(str(e).split())[:200])
'''


def _run_api_case(fork_worker, files, data, family):
    name = data.draw(st.sampled_from(API))
    args = data.draw(st.lists(st.sampled_from(VALUES), max_size=4))
    count_case(family)
    text = ", ".join(args)
    paths = (files["pack"], files["cert"], files["key"], files["junk"], files["cache"])
    code = API_CASE.format(paths=paths, needs_room="ROOM" in args, name=name, args=text)
    o = fork_worker.run({"kind": "python", "code": code, "cwd": files["dir"]}, timeout=90)
    assert o.code == 0 and not o.timeout, f"serve.{name}({text}): {o.describe()}"


@fuzz_settings(40)
@given(data=st.data())
def test_fuzz_serve_api(fork_worker, files, data):
    _run_api_case(fork_worker, files, data, "serve-api")


@pytest.mark.fuzz
@long_only
@fuzz_settings(40, long_examples=1000, long=True)
@given(data=st.data())
def test_fuzz_serve_api_long(fork_worker, files, data):
    _run_api_case(fork_worker, files, data, "serve-api-long")

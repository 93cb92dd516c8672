"""`gigascroll serve` against requests and options its first tests did not try: an
unsatisfiable Range (a 416 with its log line, like every other 4xx), `Expect: 100-continue`
on a batch too large to take (refused before the body is sent), TLS files that are not regular
files (a FIFO would block the start forever), a --cache-dir that is not a directory (refused
before a bake of minutes) and a damaged glb in the cache (baked again, not served)."""

from __future__ import annotations

import json
import logging
import os
import re
import socket
import subprocess
import sys
import time
import urllib.parse

import numpy as np
import pytest

from gigascroll import build_pack
from gigascroll.experiments import pattern_image
from gigascroll.serve import ServerThread, baked_room, make_app, pack_hash
from gigascroll.serve import room_bake
from gigascroll.serve.client_files import CLIENT_DIR


@pytest.fixture(scope="module")
def pack_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("audit-serve")
    build_pack(pattern_image(300, 120), root / "p.pack", tile_size=32, border=2)
    return root / "p.pack"


@pytest.fixture(scope="module")
def served(pack_dir):
    """(pack, url) of a tiles-only server of the small pack, in this process (its log lines
    reach caplog)."""
    from gigascroll import TilePack
    pack = TilePack(str(pack_dir))
    with ServerThread(make_app(pack)) as url:
        yield pack, url.rstrip("/")


def _exchange(url: str, request: bytes, read_until: bytes | None = None) -> bytes:
    """Sends `request` and reads the answer (up to `read_until` when given, else to EOF)."""
    u = urllib.parse.urlsplit(url)
    with socket.create_connection((u.hostname, u.port), timeout=20) as s:
        s.sendall(request)
        data = b""
        while (chunk := s.recv(65536)) and not (read_until and read_until in data + chunk):
            data += chunk
        return data + chunk


def _serve_lines(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "gigascroll.serve"]


def test_ranges_of_client_files(served, caplog):
    _, url = served
    whole = (CLIENT_DIR / "main.js").read_bytes()
    get = b"GET /client/main.js HTTP/1.1\r\nHost: x\r\nConnection: close\r\nRange: %s\r\n\r\n"
    answer = _exchange(url, get % b"bytes=5-14")
    head, body = answer.split(b"\r\n\r\n", 1)
    assert head.startswith(b"HTTP/1.1 206") and body == whole[5:15]
    assert _serve_lines(caplog) == []
    with caplog.at_level(logging.INFO, logger="gigascroll.serve"):
        answer = _exchange(url, get % f"bytes={len(whole) + 10}-".encode())
    assert answer.startswith(b"HTTP/1.1 416")
    lines = _serve_lines(caplog)
    assert len(lines) == 1 and lines[0].startswith("416 GET '/client/main.js'"), lines


def test_expect_continue_refuses_a_too_large_batch_before_its_body(served, caplog):
    pack, url = served
    h = pack_hash(pack).encode()
    head = (b"POST /api/tiles/%s/batch HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\n"
            b"Content-Length: %d\r\n\r\n")
    with caplog.at_level(logging.INFO, logger="gigascroll.serve"):
        answer = _exchange(url, head % (h, 10_000_000), read_until=b"bytes\n")
    assert answer.startswith(b"HTTP/1.1 413"), answer[:80]  # no "100 Continue" first
    assert [line[:4] for line in _serve_lines(caplog)] == ["413 "]
    # A batch within the limit is told to continue, and its tiles are the core's.
    keys = [[0, 0, 1, 0], [0, 1, 0, 0]]
    body = json.dumps({"keys": keys}).encode()
    u = urllib.parse.urlsplit(url)
    with socket.create_connection((u.hostname, u.port), timeout=20) as s:
        s.sendall(head.replace(b"\r\n\r\n", b"\r\nConnection: close\r\n\r\n") % (h, len(body)))
        assert s.recv(4096) == b"HTTP/1.1 100 Continue\r\n\r\n"
        s.sendall(body)
        data = b""
        while chunk := s.recv(65536):
            data += chunk
    status, tiles = data.split(b"\r\n\r\n", 1)
    assert status.startswith(b"HTTP/1.1 200")
    assert tiles == b"".join(pack.read_tile(*k).tobytes() for k in keys)


def test_tls_files_must_be_regular_files(tmp_path, pack_dir):
    fifo = tmp_path / "cert.fifo"
    os.mkfifo(fifo)
    big = tmp_path / "big.pem"
    with open(big, "wb") as f:
        f.truncate(8 << 20)
    for cert, word in ((fifo, "a FIFO"), ("/dev/zero", "a character device"),
                       (tmp_path, "a directory"), (big, "not a PEM file")):
        r = subprocess.run([sys.executable, "-m", "gigascroll", "serve", str(pack_dir), "--room",
                            "scroll", "--port", "0", "--tls-cert", str(cert), "--tls-key",
                            str(cert)], capture_output=True, text=True, timeout=120)
        assert r.returncode == 2 and word in r.stderr, r.stderr
        assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


def _no_bake(*args, **kwargs):
    raise AssertionError("baked although the cache directory is unusable")


@pytest.mark.parametrize("kind", ["file", "device", "under a file"])
def test_cache_dir_not_a_directory_fails_before_the_bake(tmp_path, pack_dir, monkeypatch, kind):
    from gigascroll import TilePack
    monkeypatch.setattr(room_bake, "bake_glb", _no_bake)
    (tmp_path / "f").write_text("x")
    cache = {"file": tmp_path / "f", "device": "/dev/null", "under a file": tmp_path / "f" / "c"}[kind]
    pack = TilePack(str(pack_dir))
    with pytest.raises(OSError, match="cache directory"):
        baked_room("scroll", pack, pack_hash(pack), cache_dir=cache)
    assert (tmp_path / "f").read_text() == "x"


def _small_glb() -> bytes:
    """A whole GLB: its header's length equals its size (a JSON chunk only)."""
    doc = json.dumps({"asset": {"version": "2.0"}}).encode()
    doc += b" " * (-len(doc) % 4)
    chunk = len(doc).to_bytes(4, "little") + b"JSON" + doc
    return b"glTF" + (2).to_bytes(4, "little") + (12 + len(chunk)).to_bytes(4, "little") + chunk


def test_a_damaged_cache_entry_is_baked_again(tmp_path, pack_dir, monkeypatch):
    from gigascroll import TilePack
    calls = []
    glb = _small_glb()
    monkeypatch.setattr(room_bake, "bake_glb",
                        lambda *a, **k: calls.append(1) or (glb, {"bake_points": 1, "photon_seconds": 0,
                                                                  "build_seconds": 0, "bake_seconds": 0}))
    pack = TilePack(str(pack_dir))
    h = pack_hash(pack)
    first = baked_room("scroll", pack, h, cache_dir=tmp_path)
    assert not first.cache_hit and first.glb_path.read_bytes() == glb and len(calls) == 1
    assert baked_room("scroll", pack, h, cache_dir=tmp_path).cache_hit and len(calls) == 1
    for damaged in (glb[:-4], b"", b"PNG\0" + glb[4:], glb + b"\0" * 4):
        first.glb_path.write_bytes(damaged)
        again = baked_room("scroll", pack, h, cache_dir=tmp_path)
        assert not again.cache_hit and again.glb_path.read_bytes() == glb
    assert len(calls) == 5
    header = np.frombuffer(first.glb_path.read_bytes()[:12], "<u4")
    assert header[2] == first.glb_path.stat().st_size


# ----------------------------------------------------------------------------- many clients

@pytest.fixture(scope="module")
def big_tiles(tmp_path_factory):
    """A pack of 128-px tiles (a 64-tile batch is 3 MiB) and its key list."""
    from gigascroll import TilePack
    root = tmp_path_factory.mktemp("audit-serve-big")
    build_pack(pattern_image(2000, 300), root / "p.pack")
    pack = TilePack(str(root / "p.pack"))
    keys = [[0, 0, x, y] for x in range(pack.paintings[0].level_tiles[0][0])
            for y in range(pack.paintings[0].level_tiles[0][1]) if pack.has_tile(0, 0, x, y)]
    return pack, (keys * 64)[:64]


def _batch_request(h: str, keys) -> bytes:
    body = json.dumps({"keys": keys}).encode()
    return (b"POST /api/tiles/%s/batch HTTP/1.1\r\nHost: x\r\nContent-Length: %d\r\n\r\n"
            % (h.encode(), len(body)) + body)


def _read_response(s: socket.socket) -> tuple[bytes, bytes]:
    """(head, body) of one response with a Content-Length, leaving the connection open."""
    data = b""
    while b"\r\n\r\n" not in data:
        data += s.recv(65536)
    head, body = data.split(b"\r\n\r\n", 1)
    length = int(next(line.split(b":")[1] for line in head.split(b"\r\n")
                      if line.lower().startswith(b"content-length")))
    while len(body) < length:
        body += s.recv(1 << 20)
    return head, body


def test_open_connections_do_not_keep_their_last_batch(big_tiles):
    """A keep-alive connection that stays open after its batch holds no copy of it: the
    server's traced memory after 20 such connections is far below 20 batches (it was 20)."""
    import tracemalloc
    pack, keys = big_tiles
    h = pack_hash(pack)
    expected = b"".join(pack.read_tile(*k).tobytes() for k in keys)
    with ServerThread(make_app(pack)) as url:
        u = urllib.parse.urlsplit(url)
        tracemalloc.start()
        try:
            before = tracemalloc.get_traced_memory()[0]
            socks = []
            for _ in range(20):
                s = socket.create_connection((u.hostname, u.port), timeout=30)
                s.sendall(_batch_request(h, keys))
                head, body = _read_response(s)
                assert head.startswith(b"HTTP/1.1 200") and body == expected
                socks.append(s)
            held = tracemalloc.get_traced_memory()[0] - before
        finally:
            tracemalloc.stop()
            for s in socks:
                s.close()
    assert held < 4 * len(expected), f"{held / 2**20:.0f} MiB held by 20 idle connections"


def test_head_of_a_tile_is_headers_only(big_tiles):
    pack, keys = big_tiles
    h = pack_hash(pack)
    tile = "/api/tiles/%s/%d/%d/%d/%d" % (h, *keys[0])
    with ServerThread(make_app(pack)) as url:
        answer = _exchange(url, f"HEAD {tile} HTTP/1.1\r\nHost: x\r\n\r\nGET {tile} HTTP/1.1\r\n"
                                f"Host: x\r\nConnection: close\r\n\r\n".encode())
    head1, rest = answer.split(b"\r\n\r\n", 1)
    head2, body = rest.split(b"\r\n\r\n", 1)  # the HEAD answer sent no body before this
    assert head1.startswith(b"HTTP/1.1 200") and b"Content-Length: 49152" in head1
    assert head2.startswith(b"HTTP/1.1 200") and body == pack.read_tile(*keys[0]).tobytes()


def test_clients_that_never_read_are_dropped_not_waited_for(big_tiles, monkeypatch, caplog):
    """Two slots, four clients asking for 3 MiB batches and reading nothing: another client's
    tile request gets a 429 with Retry-After while the slots are held, never a hang; the slow
    clients holding slots are disconnected after their deadline, each with one log line,
    every slot comes back and the tile is then served with the core's bytes."""
    from gigascroll.serve import app as app_module
    pack, keys = big_tiles
    h = pack_hash(pack)
    monkeypatch.setattr(app_module, "SLOT_WAIT_S", 0.5)
    monkeypatch.setattr(app_module, "SEND_GRACE_S", 1.0)
    monkeypatch.setattr(app_module, "SEND_MIN_RATE", 1 << 20)  # 3 MiB: 4 s in all
    app = make_app(pack, max_inflight=2)
    tile = f"/api/tiles/{h}/0/0/0/0"
    get = f"GET {tile} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n".encode()
    with caplog.at_level(logging.INFO, logger="gigascroll.serve"), ServerThread(app) as url:
        u = urllib.parse.urlsplit(url)
        slow = []
        for _ in range(4):
            s = socket.socket()
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # before connect: a small window
            s.connect((u.hostname, u.port))
            s.sendall(_batch_request(h, keys))
            slow.append(s)
        busy = _exchange(url, get)
        assert busy.startswith(b"HTTP/1.1 429") and b"Retry-After: 1" in busy, busy[:200]
        for _ in range(200):  # the deadlines pass: every slot returns
            if app[app_module.STATE_KEY].inflight._value == 2 and len(
                    [m for m in _serve_lines(caplog) if "client too slow" in m]) == 2:
                break
            time.sleep(0.1)
        answer = _exchange(url, get)
        for s in slow:
            s.close()
    assert answer.startswith(b"HTTP/1.1 200")
    assert answer.split(b"\r\n\r\n", 1)[1] == pack.read_tile(0, 0, 0, 0).tobytes()
    lines = _serve_lines(caplog)
    # Two held the slots until their deadline; the two others waited for one and got a 429.
    assert sum("client too slow" in m for m in lines) == 2, lines
    assert sum(m.startswith("429 POST") for m in lines) == 2, lines
    assert app[app_module.STATE_KEY].inflight._value == 2
    assert not any("Traceback" in r.getMessage() or r.exc_info for r in caplog.records)


def test_server_thread_misuse_is_a_value_error(pack_dir):
    """A second start, an app another ServerThread serves and a bad port are ValueErrors;
    stop() from four threads at once (and again later) stops once, without an error."""
    import threading
    from gigascroll import TilePack
    pack = TilePack(str(pack_dir))
    for port in (-1, 65536, True, "80", 1.5):
        with pytest.raises(ValueError, match="port"):
            ServerThread(make_app(pack), port=port)
    app = make_app(pack)
    server = ServerThread(app)
    url = server.start()
    with pytest.raises(ValueError, match="started already"):
        server.start()
    with pytest.raises(ValueError, match="served already"):
        ServerThread(app).start()
    errors = []

    def stop():
        try:
            server.stop()
        except BaseException as e:  # noqa: BLE001 - collected for the assert
            errors.append(e)
    threads = [threading.Thread(target=stop) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    server.stop()
    assert errors == [] and not any(t.is_alive() for t in threads)
    u = urllib.parse.urlsplit(url)
    with pytest.raises(OSError):  # nothing listens there any more
        socket.create_connection((u.hostname, u.port), timeout=5).close()


def test_a_damaged_glb_in_a_show_is_not_rebaked_into_the_show(tmp_path, pack_dir):
    """serve --exhibition reads the show's bake/ only when its glb is whole: a damaged one is
    baked again into the user's cache, never written into the show."""
    from types import SimpleNamespace
    from gigascroll import TilePack
    from gigascroll.commands.serve import _cache_dir
    from gigascroll.gallery.quality import light_settings
    from gigascroll.room.builtin import builtin_room
    from gigascroll.serve.room_bake import lighting_options, room_key
    pack = TilePack(str(pack_dir))
    h = pack_hash(pack)
    spec = builtin_room("scroll", pack)
    show = SimpleNamespace(path=tmp_path / "show", room=spec)
    glb = tmp_path / "show" / "bake" / f"{room_key(spec, h, lighting_options(light_settings(spec)))}.glb"
    glb.parent.mkdir(parents=True)
    args = SimpleNamespace(cache_dir=None)
    assert _cache_dir(args, show, h) is None                 # no glb: the user cache
    glb.write_bytes(_small_glb())
    assert _cache_dir(args, show, h) == glb.parent           # whole: the show's
    glb.write_bytes(_small_glb()[:-4])
    assert _cache_dir(args, show, h) is None                 # damaged: the user cache
    assert _cache_dir(SimpleNamespace(cache_dir=str(tmp_path)), show, h) == str(tmp_path)


def test_out_of_descriptors_is_a_few_lines_and_passes(tmp_path, pack_dir):
    """Idle connections past the process's open-file limit: asyncio's accept error was logged
    with a traceback at every retry (thousands of lines); now one line every 10 s, and the
    server serves again once they close. serve also raises its soft limit to the hard one."""
    import resource
    import urllib.request
    from serve_support import ServeProcess

    from gigascroll import TilePack

    def limit():  # soft 48, hard 64: serve raises the soft one to 64
        resource.setrlimit(resource.RLIMIT_NOFILE, (48, 64))

    real_popen = subprocess.Popen

    def popen(*args, **kwargs):
        return real_popen(*args, preexec_fn=limit, **kwargs)
    subprocess.Popen = popen
    try:
        proc = ServeProcess([pack_dir, "--room", "scroll", "--port", "0", "--cache-dir",
                             tmp_path / "cache"], tmp_path)
    finally:
        subprocess.Popen = real_popen
    try:
        limits = open(f"/proc/{proc.pid}/limits").read()
        assert re.search(r"Max open files\s+64\s+64", limits), limits
        u = urllib.parse.urlsplit(proc.url)
        idle = []
        for _ in range(100):
            try:
                idle.append(socket.create_connection((u.hostname, u.port), timeout=2))
            except OSError:
                break
        time.sleep(3)  # the server meets the limit, retrying its accept
        for s in idle:
            s.close()
        time.sleep(1.5)
        with urllib.request.urlopen(proc.url + "/api/scene.json", timeout=30) as r:
            assert json.load(r)["pack"]["hash"] == pack_hash(TilePack(str(pack_dir)))
    finally:
        code = proc.stop()
    log = proc.stderr()
    assert code == 0 and "Traceback" not in log, log[-2000:]
    assert 1 <= log.count("out of system resource") <= 3, log[-2000:]


def test_ctrl_c_does_not_wait_for_clients_that_stopped_reading(tmp_path, big_tiles):
    """SIGINT with six clients that asked for 3 MiB batches and read nothing, and idle ones:
    the server exits 0 with its 'stopped' line within a few seconds (aiohttp's default
    shutdown wait let them hold it for about a minute; a hang fails here by the timeout)."""
    import signal
    from serve_support import ServeProcess
    pack, keys = big_tiles
    proc = ServeProcess([pack.path, "--room", "scroll", "--port", "0", "--cache-dir",
                         tmp_path / "cache"], tmp_path)
    u = urllib.parse.urlsplit(proc.url)
    held = []
    try:
        for _ in range(6):
            s = socket.socket()
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            s.connect((u.hostname, u.port))
            s.sendall(_batch_request(pack_hash(pack), keys))
            held.append(s)
        held += [socket.create_connection((u.hostname, u.port)) for _ in range(4)]
        time.sleep(1)
        code = proc.stop(signal.SIGINT, timeout=30)  # kills (code -9) when it does not stop
    finally:
        for s in held:
            s.close()
    log = proc.stderr()
    assert code == 0 and "stopped (SIGINT)" in log and "Traceback" not in log, log[-2000:]

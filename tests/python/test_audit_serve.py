"""`gigascroll serve` against requests and options its first tests did not try: an
unsatisfiable Range (a 416 with its log line, like every other 4xx), `Expect: 100-continue`
on a batch too large to take (refused before the body is sent), TLS files that are not regular
files (a FIFO would block the start forever), a --cache-dir that is not a directory (refused
before a bake of minutes) and a damaged glb in the cache (baked again, not served)."""

from __future__ import annotations

import json
import logging
import os
import socket
import subprocess
import sys
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

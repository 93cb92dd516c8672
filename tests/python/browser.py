"""The browser test harness: Debian's chromium, headless with WebGL2 on SwiftShader, driven from
Python through Playwright (launched on the system chromium: Playwright downloads no browser),
and a server for a pack and the client's files.

Fixtures (import them into a test module: ``from browser import browser, chromium_path``):

- ``chromium_path``: the system chromium, or the test skips with the reason;
- ``browser``: one headless chromium for the session (``browser.new_page()``).

``serve_pack(pack_path)`` is a context manager yielding the base URL of a server for the pack:
``gigascroll serve`` on 127.0.0.1 and a free port when the command exists, else
:class:`StubServer`, the protocol's static part (client files, ``/api/scene.json``'s pack,
tiles and batches, docs/serve-protocol.md) from the standard library, read through the core's
``TilePack.read_tile``.
"""

from __future__ import annotations

import contextlib
import hashlib
import http.server
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

WEB_DIR = Path(__file__).resolve().parents[2] / "python" / "gigascroll" / "web"

CHROMIUM_ARGS = ["--headless=new", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                 "--no-sandbox", "--enable-webgl", "--ignore-gpu-blocklist"]


def find_chromium() -> str | None:
    """The system chromium's path ($GIGASCROLL_CHROMIUM first), or None."""
    for name in (os.environ.get("GIGASCROLL_CHROMIUM"), "chromium", "chromium-browser"):
        if name and (path := shutil.which(name)):
            return path
    return None


@pytest.fixture(scope="session")
def chromium_path():
    path = find_chromium()
    if path is None:
        pytest.skip("chromium not found (the Makefile installs Debian's chromium)")
    return path


@pytest.fixture(scope="session")
def browser(chromium_path):
    """A headless chromium with WebGL2 on SwiftShader, for the whole session."""
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium_path, headless=True, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


def open_page(browser, url: str, ready: str = "window.vtTestReady === true", timeout_s: float = 60):
    """A new page at url, after `ready` (a JS expression) holds; console errors are kept in
    page.errors and raised here if the page failed before it was ready."""
    page = browser.new_page()
    page.errors = []
    page.on("console", lambda m: m.type == "error" and page.errors.append(m.text))
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    page.goto(url)
    try:
        page.wait_for_function(ready, timeout=timeout_s * 1000)
    except Exception as e:
        raise AssertionError(f"page {url} not ready: {page.errors}") from e
    return page


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pack_description(pack, pack_hash: str) -> dict:
    """scene.json's "pack" (docs/serve-protocol.md) from an open TilePack."""
    paintings = []
    for i, p in enumerate(pack.paintings):
        paintings.append({
            "index": i, "name": p.name, "width": p.width, "height": p.height, "levels": p.levels,
            "level_sizes": [list(s) for s in p.level_sizes],
            "level_tiles": [list(t) for t in p.level_tiles],
            "table_size": list(p.table_size), "table_offset": list(p.table_offset),
            "uv_scale": list(p.uv_scale)})
    return {"hash": pack_hash, "tile_size": pack.tile_size, "border": pack.border,
            "payload": pack.payload, "table_size": list(pack.table_size), "paintings": paintings}


class StubServer:
    """The protocol's static part for one pack on 127.0.0.1 (a thread): until `gigascroll
    serve` exists, and for tests that need no room."""

    def __init__(self, pack_path):
        from gigascroll import TilePack
        self.pack = TilePack(str(pack_path))
        self.hash = hashlib.sha256(self.pack.manifest_json().encode()).hexdigest()[:16]
        self.scene = {"version": 1, "pack": pack_description(self.pack, self.hash),
                      "tiles": {"tile": f"/api/tiles/{self.hash}/{{painting}}/{{level}}/{{tx}}/{{ty}}",
                                "batch": f"/api/tiles/{self.hash}/batch", "max_batch": 64}}
        self.lock = threading.Lock()  # the reader is not shared between request threads
        handler = self._handler()
        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)

    def tile(self, key) -> bytes:
        p, l, x, y = (int(k) for k in key)
        with self.lock:
            return self.pack.read_tile(p, l, x, y).tobytes()

    def _handler(self):
        server = self
        types = {".js": "text/javascript", ".html": "text/html", ".json": "application/json",
                 ".css": "text/css", ".glsl": "text/plain"}

        class Handler(http.server.BaseHTTPRequestHandler):
            def log_message(self, *args):
                pass

            def reply(self, code, body: bytes, ctype="text/plain"):
                self.send_response(code)
                self.send_header("Content-Type", ctype)
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def do_GET(self):
                path = self.path.split("?")[0]
                if path == "/api/scene.json":
                    return self.reply(200, json.dumps(server.scene).encode(), types[".json"])
                if m := re.fullmatch(r"/client/((?:[\w-]+/)*[\w.-]+)", path):
                    f = (WEB_DIR / m.group(1)).resolve()
                    if WEB_DIR in f.parents and f.is_file() and ".." not in m.group(1):
                        return self.reply(200, f.read_bytes(), types.get(f.suffix, "text/plain"))
                if m := re.fullmatch(rf"/api/tiles/{server.hash}/(\d+)/(\d+)/(\d+)/(\d+)", path):
                    try:
                        return self.reply(200, server.tile(m.groups()), "application/octet-stream")
                    except Exception as e:  # noqa: BLE001 - a bad key is a 404 here
                        return self.reply(404, str(e).encode())
                self.reply(404, b"not found")

            def do_POST(self):
                if self.path != f"/api/tiles/{server.hash}/batch":
                    return self.reply(404, b"not found")
                n = int(self.headers.get("Content-Length", 0))
                try:
                    keys = json.loads(self.rfile.read(n))["keys"]
                    body = b"".join(server.tile(k) for k in keys[:64])
                except Exception as e:  # noqa: BLE001
                    return self.reply(404, str(e).encode())
                self.reply(200, body, "application/octet-stream")

        return Handler

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.httpd.shutdown()
        self.httpd.server_close()
        self.pack.close() if hasattr(self.pack, "close") else None
        return False


def _serve_command_exists() -> bool:
    r = subprocess.run([sys.executable, "-m", "gigascroll", "serve", "--help"],
                       capture_output=True, text=True)
    return r.returncode == 0


@contextlib.contextmanager
def serve_pack(pack_path, room: str | None = None, stub: bool | None = None):
    """Yields the base URL of a server for the pack (see the module's docstring)."""
    if stub is None:
        stub = room is None or not _serve_command_exists()
    if stub:
        with StubServer(pack_path) as s:
            yield s.url
        return
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "gigascroll", "serve", str(pack_path),
                             "--room", room, "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                raise RuntimeError(f"gigascroll serve exited: {proc.stdout.read()}")
            with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.2):
                break
            time.sleep(0.2)
        yield url
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()

"""The browser test harness: Debian's chromium, headless with WebGL2 on SwiftShader, driven from
Python through Playwright (launched on the system chromium: Playwright downloads no browser),
and a server for a pack and the client's files.

Fixtures (import them into a test module: ``from browser import browser, chromium_path``):

- ``chromium_path``: the system chromium, or the test skips with the reason;
- ``browser``: one headless chromium for a test module (``browser.new_page()``).

``pack_scene(pack_path)`` is the scene.json part the test page needs when no room is served.
``serve_pack(pack_path, room=None)`` is a context manager yielding the base URL of
``gigascroll serve``'s application (gigascroll.serve) for the pack on 127.0.0.1 and a free
port, in a thread of the test process.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket

import pytest

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


# One Playwright and one chromium at a time, however many test modules import the fixture:
# each import is a fixture of its own to pytest, and a second sync_playwright() in the same
# thread fails ("Sync API inside the asyncio loop"). Module-scoped, and closed when its last
# user is done, so that code under test may start its own Playwright in later modules (the
# web benchmarks do).
_shared = {"users": 0, "playwright": None, "browser": None}


@pytest.fixture(scope="module")
def browser(chromium_path):
    """A headless chromium with WebGL2 on SwiftShader, for a test module."""
    from playwright.sync_api import sync_playwright  # the Makefile installs it: no skip

    if _shared["browser"] is None:
        _shared["playwright"] = sync_playwright().start()
        _shared["browser"] = _shared["playwright"].chromium.launch(
            executable_path=chromium_path, headless=True, args=CHROMIUM_ARGS)
    _shared["users"] += 1
    try:
        yield _shared["browser"]
    finally:
        _shared["users"] -= 1
        if _shared["users"] == 0:
            _shared["browser"].close()
            _shared["playwright"].stop()
            _shared["browser"] = _shared["playwright"] = None


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


def pack_scene(pack_path) -> dict:
    """scene.json's pack and tiles parts for a pack served without a room (the server answers
    /api/scene.json only with a room): what the virtual texture's test page needs."""
    from gigascroll import TilePack
    from gigascroll.serve import MAX_BATCH, pack_description, pack_hash

    pack = TilePack(str(pack_path))
    h = pack_hash(pack)
    return {"version": 1, "pack": pack_description(pack, h),
            "tiles": {"tile": f"/api/tiles/{h}/{{painting}}/{{level}}/{{tx}}/{{ty}}",
                      "batch": f"/api/tiles/{h}/batch", "max_batch": MAX_BATCH}}


@contextlib.contextmanager
def serve_pack(pack_path, room: str | None = None, cache_dir=None):
    """Yields the base URL of `gigascroll serve`'s application for the pack (and the room,
    baked or read from cache_dir, when given) on 127.0.0.1 and a free port, in a thread."""
    from gigascroll import TilePack
    from gigascroll.serve import ServerThread, baked_room, make_app, pack_hash

    pack = TilePack(str(pack_path))
    content_hash = pack_hash(pack)
    baked = baked_room(room, pack, content_hash, cache_dir) if room else None
    with ServerThread(make_app(pack, baked, content_hash)) as url:
        yield url.rstrip("/")

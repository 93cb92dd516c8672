"""The aiohttp application of `gigascroll serve` (docs/serve-protocol.md).

    app = make_app(pack, room)        # room: a BakedRoom (room_bake.baked_room)

Tiles are read through the core reader (`TilePack.read_tile_into`: checksums verified, codecs
decoded) on a fixed pool of threads (the reads release the GIL); at most `max_inflight` tile
requests are read and written at once, each at most MAX_BATCH tiles, and request bodies are
capped at MAX_BODY: the memory a crowd of clients can pin is bounded by
max_inflight x MAX_BATCH x tile bytes. A slot is held at most send_deadline() while the bytes
go out (a client that stops reading is disconnected) and waited for at most SLOT_WAIT_S (then a
429 the client retries), so clients that never read cannot stall the others. Every bad request is a 4xx with a one-line text body
and one log line; an unexpected error is answered the same way (never a 5xx or a traceback)."""

from __future__ import annotations

import asyncio
import json
import logging
import os
import re
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from aiohttp import web

from .._core import TilePack
from ..errors import expect_type
from .client_files import CLIENT_DIR, CONTENT_TYPES, client_path
from .pack_info import pack_hash
from .scene import MAX_BATCH, scene_document

__all__ = ["make_app", "MAX_BODY", "LOG"]

LOG = logging.getLogger("gigascroll.serve")
MAX_BODY = 64 * 1024
SLOT_WAIT_S = 10.0                      # a tile request's wait for a slot, then a 429
SEND_GRACE_S, SEND_MIN_RATE = 10.0, 64 * 1024   # a response's time to go out (send_deadline)
IMMUTABLE = "public, max-age=31536000, immutable"
NUMBER = re.compile(r"[0-9]{1,9}")
PACK_KEY, ROOM_KEY, STATE_KEY = web.AppKey("pack", object), web.AppKey("room", object), \
    web.AppKey("state", object)
IIIF_KEY = web.AppKey("iiif_dir", object)


def _one_line(text: str, limit: int = 200) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit] + "..."


def _fail(cls, message: str):
    """An HTTP error whose body is one line of plain text."""
    return cls(text=message + "\n", content_type="text/plain")


def _too_large(message: str, size: int):
    return web.HTTPRequestEntityTooLarge(max_size=MAX_BODY, actual_size=size,
                                         text=message + "\n", content_type="text/plain")


LOGGED = web.RequestKey("logged", bool)  # set on a request whose error has had its log line


@web.middleware
async def one_line_errors(request: web.Request, handler):
    """Every error as a 4xx with a one-line body and one log line: HTTP errors keep their
    status, anything unexpected becomes a 400 (the log line says what it was)."""
    try:
        return await handler(request)
    except web.HTTPException as e:
        if e.status >= 400:
            reason = e.text.strip() if e.text else e.reason
            LOG.warning("%d %s %s: %s", e.status, request.method, _one_line(repr(request.path_qs)),
                        _one_line(reason))
            request[LOGGED] = True
            if not e.text or e.text.strip() == f"{e.status}: {e.reason}":
                e.text = f"{e.status} {e.reason}\n"
        raise
    except asyncio.CancelledError:
        raise
    except ConnectionError:  # the client left while its request was read: nobody to answer
        LOG.info("%s %s: client left", request.method, _one_line(repr(request.path_qs)))
        request[LOGGED] = True
        return web.Response(status=400, text="connection lost\n")
    except Exception as e:  # noqa: BLE001 (the promise: no 5xx, no traceback)
        LOG.warning("400 %s %s: unexpected %s: %s", request.method,
                    _one_line(repr(request.path_qs)), type(e).__name__, _one_line(e))
        request[LOGGED] = True
        return web.Response(status=400, text=f"bad request ({type(e).__name__})\n")


async def log_other_errors(request: web.Request, response: web.StreamResponse) -> None:
    """The log line of a 4xx that no handler raised: a file response's 416 to an
    unsatisfiable Range, expect_small_body's 413."""
    if response.status >= 400 and not request.get(LOGGED):
        request[LOGGED] = True
        LOG.warning("%d %s %s: %s", response.status, request.method,
                    _one_line(repr(request.path_qs)), _one_line(response.reason or ""))


async def expect_small_body(request: web.Request):
    """`Expect: 100-continue` on a batch: a body over MAX_BODY is refused at once with a 413,
    before the client sends it; anything else is told to continue."""
    if request.content_length is not None and request.content_length > MAX_BODY:
        response = web.Response(status=413, text=f"body over {MAX_BODY} bytes\n")
        response.force_close()  # the body is never read: the connection cannot go on
        return response
    if request.version != (1, 1):  # as aiohttp's own handler: HTTP/1.0 has no 100 Continue
        return None
    if request.headers.get("Expect", "").lower() != "100-continue":
        return web.Response(status=417, text="only Expect: 100-continue is understood\n")
    await request.writer.write(b"HTTP/1.1 100 Continue\r\n\r\n")
    request.writer.output_size = 0
    return None


class _State:
    """What the handlers share: the pack's numbers for checking keys, the reader's thread
    pool and the bound on tile requests in flight."""

    def __init__(self, pack, content_hash: str, room, client_dir, read_threads: int,
                 max_inflight: int, display=None):
        self.pack, self.hash, self.room, self.client_dir = pack, content_hash, room, client_dir
        self.tile_shape = (pack.tile_size, pack.tile_size, 3)
        self.tile_bytes = pack.tile_size * pack.tile_size * 3
        self.level_tiles = [list(p.level_tiles) for p in pack.paintings]
        self.pool = ThreadPoolExecutor(max_workers=read_threads, thread_name_prefix="serve-read")
        self.inflight = asyncio.Semaphore(max_inflight)
        self.scene = (json.dumps(scene_document(pack, content_hash, room, display)).encode()
                      if room else None)
        self.etag_prefix = f'"{content_hash}'

    def check_key(self, key) -> tuple[int, int, int, int]:
        """(painting, level, tx, ty) of a stored tile; HTTPNotFound otherwise."""
        p, level, tx, ty = key
        if not (0 <= p < len(self.level_tiles) and 0 <= level < len(self.level_tiles[p])):
            raise _fail(web.HTTPNotFound, f"no tile {tuple(key)} in the pack")
        nx, ny = self.level_tiles[p][level]
        if not (0 <= tx < nx and 0 <= ty < ny) or not self.pack.has_tile(p, level, tx, ty):
            raise _fail(web.HTTPNotFound, f"no tile {tuple(key)} in the pack")
        return p, level, tx, ty

    def read(self, keys: list[tuple[int, int, int, int]]) -> bytearray:
        """The tiles' bytes back to back (on a pool thread; the core releases the GIL)."""
        out = bytearray(len(keys) * self.tile_bytes)
        view = np.frombuffer(out, np.uint8).reshape((len(keys),) + self.tile_shape)
        for k, key in enumerate(keys):
            self.pack.read_tile_into(*key, view[k])
        return out

    async def send_tiles(self, request, keys, headers) -> web.StreamResponse:
        """Reads and writes the tiles within the bound on requests in flight. A slot is waited
        for at most SLOT_WAIT_S (then a 429: retry), and held while the bytes go out for at
        most send_deadline(): a client that stops reading is dropped, so a few of them cannot
        hold every slot (and the tiles' memory) for ever."""
        try:
            await asyncio.wait_for(self.inflight.acquire(), SLOT_WAIT_S)
        except asyncio.TimeoutError:
            raise web.HTTPTooManyRequests(
                text=f"every tile slot busy for {SLOT_WAIT_S:g} s; retry\n",
                content_type="text/plain", headers={"Retry-After": "1"}) from None
        try:
            try:
                body = await asyncio.get_running_loop().run_in_executor(self.pool, self.read, keys)
            except (OSError, ValueError) as e:  # a damaged pack: the tile cannot be served
                raise _fail(web.HTTPNotFound, f"tile unreadable: {_one_line(e)}") from None
            resp = web.StreamResponse(headers=headers)
            resp.content_type, resp.content_length = "application/octet-stream", len(body)
            try:
                await asyncio.wait_for(_send(resp, request, body), send_deadline(len(body)))
            except (asyncio.TimeoutError, ConnectionError) as e:
                _drop(request, e, len(body))
            return resp
        finally:
            self.inflight.release()


def send_deadline(size: int) -> float:
    """Seconds a response of `size` bytes may take to go out: SEND_GRACE_S plus the time at
    SEND_MIN_RATE bytes a second (a 64-tile batch of 128-px tiles: about 58 s)."""
    return SEND_GRACE_S + size / SEND_MIN_RATE


async def _send(resp: web.StreamResponse, request: web.Request, body: bytearray) -> None:
    """Writes `body` through a StreamResponse, which keeps no reference to it: a Response
    would hold its body for as long as the keep-alive connection stays open, 3 MB a
    connection that never closes."""
    await resp.prepare(request)
    if request.method != "HEAD":  # a HEAD answer is its headers only
        await resp.write(body)
    await resp.write_eof()


def _drop(request: web.Request, e: BaseException, size: int) -> None:
    """One log line for a client that left, or that read too slowly and is disconnected."""
    what = (f"client too slow: {size} bytes not taken in {send_deadline(size):.0f} s, "
            "disconnected") if isinstance(e, asyncio.TimeoutError) else "client left before the tiles were sent"
    LOG.warning("%s %s: %s", request.method, _one_line(repr(request.path_qs)), what)
    if request.transport is not None:
        request.transport.abort()


def _state(request) -> _State:
    return request.app[STATE_KEY]


def _number(text: str, what: str) -> int:
    if not NUMBER.fullmatch(text):
        raise _fail(web.HTTPBadRequest, f"{what} must be a decimal number, got {_one_line(text, 40)!r}")
    return int(text)


def _check_hash(state: _State, request) -> None:
    if request.match_info["hash"] != state.hash:
        raise _fail(web.HTTPNotFound, "not the served pack's hash")


async def tile(request: web.Request) -> web.StreamResponse:
    state = _state(request)
    m = request.match_info
    key = tuple(_number(m[n], n) for n in ("painting", "level", "tx", "ty"))
    _check_hash(state, request)
    key = state.check_key(key)
    etag = f'{state.etag_prefix}-{key[0]}-{key[1]}-{key[2]}-{key[3]}"'
    headers = {"Cache-Control": IMMUTABLE, "ETag": etag}
    if etag in request.headers.get("If-None-Match", ""):
        return web.Response(status=304, headers=headers)
    return await state.send_tiles(request, [key], headers)


async def batch(request: web.Request) -> web.StreamResponse:
    state = _state(request)
    _check_hash(state, request)
    if request.content_length is not None and request.content_length > MAX_BODY:
        raise _too_large(f"body over {MAX_BODY} bytes", request.content_length)
    try:
        doc = json.loads(await request.read())
    except (ValueError, RecursionError):
        raise _fail(web.HTTPBadRequest, 'body must be JSON {"keys": [[painting, level, tx, ty], ...]}') from None
    keys = doc.get("keys") if isinstance(doc, dict) else None
    if not isinstance(keys, list):
        raise _fail(web.HTTPBadRequest, 'body must be JSON {"keys": [[painting, level, tx, ty], ...]}')
    if len(keys) > MAX_BATCH:
        raise _too_large(f"{len(keys)} keys: at most {MAX_BATCH} a batch", request.content_length or 0)
    for k in keys:
        if not (isinstance(k, list) and len(k) == 4
                and all(type(x) is int and 0 <= x < 1 << 31 for x in k)):
            raise _fail(web.HTTPBadRequest, f"a key must be 4 non-negative integers, got {_one_line(repr(k), 80)}")
    keys = [state.check_key(tuple(k)) for k in keys]
    return await state.send_tiles(request, keys, {"Cache-Control": "no-store"})


async def scene(request: web.Request) -> web.Response:
    state = _state(request)
    if state.scene is None:
        raise _fail(web.HTTPNotFound, "no room is served")
    return web.Response(body=state.scene, content_type="application/json",
                        headers={"Cache-Control": "no-cache"})


async def room_glb(request: web.Request) -> web.StreamResponse:
    state = _state(request)
    if state.room is None or request.match_info["key"] != state.room.key:
        raise _fail(web.HTTPNotFound, "no such room")
    if not state.room.glb_path.is_file():
        raise _fail(web.HTTPNotFound, "the room's cache entry is gone")
    return web.FileResponse(state.room.glb_path, headers={
        "Cache-Control": IMMUTABLE, "Content-Type": "model/gltf-binary"})


async def client_file(request: web.Request) -> web.StreamResponse:
    state = _state(request)
    path = client_path(request.match_info.get("path", "index.html"), state.client_dir)
    if path is None:
        raise _fail(web.HTTPNotFound, "not a file of the client")
    return web.FileResponse(path, headers={"Cache-Control": "no-cache",
                                           "Content-Type": CONTENT_TYPES[path.suffix]})


IIIF_TYPES = {".json": "application/json", ".jpg": "image/jpeg"}


async def iiif_file(request: web.Request) -> web.StreamResponse:
    """A file of the show's IIIF folder (exhibit build's iiif/: the Presentation manifest, the
    Image API info.json and tiles), with CORS open as IIIF viewers on other sites need."""
    path = client_path(request.match_info["path"], request.app[IIIF_KEY], IIIF_TYPES)
    if path is None:
        raise _fail(web.HTTPNotFound, "not a file of the show's IIIF folder")
    return web.FileResponse(path, headers={"Cache-Control": "no-cache",
                                           "Content-Type": IIIF_TYPES[path.suffix],
                                           "Access-Control-Allow-Origin": "*"})


def make_app(pack, room=None, content_hash: str | None = None, client_dir=CLIENT_DIR,
             read_threads: int = 4, max_inflight: int = 16, display=None,
             iiif_dir=None) -> web.Application:
    """The application serving `pack` (an open TilePack) and `room` (a BakedRoom, or None for
    tiles only). content_hash: the pack's (computed when None). display: the camera response
    scene.json gives the client (a display_mapping.Display; None: the room's automatic one).
    iiif_dir: a show's IIIF folder, served under /iiif/ (where exhibit build's default
    --base-url points when serve listens on port 8000)."""
    from .room_bake import BakedRoom

    expect_type(pack, TilePack, "pack")
    if room is not None:
        expect_type(room, BakedRoom, "room")
    if content_hash is not None:
        expect_type(content_hash, str, "content_hash")
    client_dir = Path(expect_type(client_dir, (str, os.PathLike), "client_dir"))
    for name, value in (("read_threads", read_threads), ("max_inflight", max_inflight)):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 256:
            raise ValueError(f"{name} must be an integer in [1, 256], got {value!r}")
    app = web.Application(middlewares=[one_line_errors], client_max_size=MAX_BODY)
    state = _State(pack, content_hash or pack_hash(pack), room, client_dir, read_threads,
                   max_inflight, display)
    app[STATE_KEY] = state
    app.router.add_get("/", client_file)
    app.router.add_get("/client/{path:.+}", client_file)
    app.router.add_get("/api/scene.json", scene)
    app.router.add_get("/api/room/{key}.glb", room_glb)
    app.router.add_get("/api/tiles/{hash}/{painting}/{level}/{tx}/{ty}", tile)
    app.router.add_post("/api/tiles/{hash}/batch", batch, expect_handler=expect_small_body)
    if iiif_dir is not None:
        app[IIIF_KEY] = Path(expect_type(iiif_dir, (str, os.PathLike), "iiif_dir"))
        app.router.add_get("/iiif/{path:.+}", iiif_file)

    async def shutdown(app):
        state.pool.shutdown(wait=True, cancel_futures=True)

    app.on_cleanup.append(shutdown)
    app.on_response_prepare.append(log_other_errors)
    return app

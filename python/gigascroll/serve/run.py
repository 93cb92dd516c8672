"""Running the server: in the foreground until SIGINT or SIGTERM (`gigascroll serve`), or on a
background thread for tests and scripts (`ServerThread`)."""

from __future__ import annotations

import asyncio
import logging
import signal
import ssl
import sys
import threading

from aiohttp import web

__all__ = ["LOOPBACK_HOSTS", "tls_context", "start_site", "serve_forever", "ServerThread",
           "OneLineFormatter"]

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")


class OneLineFormatter(logging.Formatter):
    """Log records as one line each: an exception's type and message, never its traceback
    (aiohttp's own loggers pass exc_info for connection-level errors)."""

    def format(self, record: logging.LogRecord) -> str:
        message = " ".join(record.getMessage().split())
        if record.exc_info and record.exc_info[1] is not None:
            e = record.exc_info[1]
            message += f": {type(e).__name__}: {' '.join(str(e).split())}"
        return f"gigascroll serve: {message}"[:1000]


def tls_context(cert: str, key: str) -> ssl.SSLContext:
    """A server context from PEM files; OSError / ssl.SSLError (an OSError) when they are
    missing or do not hold a certificate and its key."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    ctx.load_cert_chain(cert, key)
    return ctx


def _url(site_address, tls: bool) -> str:
    host, port = site_address[0], site_address[1]
    host = f"[{host}]" if ":" in host else host
    return f"{'https' if tls else 'http'}://{host}:{port}/"


async def start_site(app: web.Application, host: str, port: int,
                     ssl_context: ssl.SSLContext | None = None) -> tuple[web.AppRunner, str]:
    """Starts `app` on host:port (0: a free port); (its runner, its URL). OSError when the
    address is taken or unavailable."""
    runner = web.AppRunner(app, access_log=None, handle_signals=False)
    await runner.setup()
    site = web.TCPSite(runner, host, port, ssl_context=ssl_context, reuse_address=True)
    try:
        await site.start()
    except BaseException:
        await runner.cleanup()
        raise
    return runner, _url(runner.addresses[0], ssl_context is not None)


def serve_forever(app: web.Application, host: str, port: int,
                  ssl_context: ssl.SSLContext | None = None, announce=print) -> str:
    """Serves until SIGINT or SIGTERM; returns the signal's name. `announce(url)` is called
    once the socket listens."""
    async def main():
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        caught = []
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, lambda s=sig: (caught.append(s), stop.set()))
        runner, url = await start_site(app, host, port, ssl_context)
        try:
            announce(url)
            await stop.wait()
        finally:
            await runner.cleanup()
        return signal.Signals(caught[0]).name

    return asyncio.run(main())


class ServerThread:
    """The app on a background thread's event loop: `with ServerThread(app) as url: ...` or
    start() -> URL and stop()."""

    def __init__(self, app: web.Application, host: str = "127.0.0.1", port: int = 0,
                 ssl_context: ssl.SSLContext | None = None):
        self.app, self.host, self.port, self.ssl_context = app, host, port, ssl_context
        self.url: str | None = None
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="serve", daemon=True)
        self._runner = None

    def start(self) -> str:
        self._thread.start()
        future = asyncio.run_coroutine_threadsafe(
            start_site(self.app, self.host, self.port, self.ssl_context), self._loop)
        try:
            self._runner, self.url = future.result(timeout=60)
        except BaseException:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join()
            raise
        return self.url

    def stop(self) -> None:
        if self._runner is not None:
            asyncio.run_coroutine_threadsafe(self._runner.cleanup(), self._loop).result(timeout=60)
            self._runner = None
        if self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join()
        if not self._loop.is_closed():
            self._loop.close()

    def __enter__(self) -> str:
        return self.start()

    def __exit__(self, *exc) -> bool:
        self.stop()
        return False


def log_to_stderr(level: int = logging.INFO) -> None:
    """One-line records of the server's and aiohttp's loggers on stderr."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(OneLineFormatter())
    for name in ("gigascroll.serve", "aiohttp"):
        logger = logging.getLogger(name)
        logger.handlers[:] = [handler]
        logger.setLevel(level)
        logger.propagate = False

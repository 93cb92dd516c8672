"""Running the server: in the foreground until SIGINT or SIGTERM (`gigascroll serve`), or on a
background thread for tests and scripts (`ServerThread`)."""

from __future__ import annotations

import asyncio
import logging
import signal
import socket
import ssl
import sys
import threading
import time

from aiohttp import web

__all__ = ["LOOPBACK_HOSTS", "tls_context", "listen_socket", "start_site", "serve_forever", "ServerThread",
           "OneLineFormatter"]

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
MAX_PEM_BYTES = 1 << 20  # a certificate chain and its key are kilobytes
# On Ctrl-C or SIGTERM, requests in flight get this long to finish before they are cancelled:
# aiohttp's default (60 s) let a client that stopped reading hold the exit for a minute.
SHUTDOWN_GRACE_S = 2.0


class OneLineFormatter(logging.Formatter):
    """Log records as one line each: an exception's type and message, never its traceback
    (aiohttp's own loggers pass exc_info for connection-level errors)."""

    def format(self, record: logging.LogRecord) -> str:
        message = " ".join(record.getMessage().split())
        if record.exc_info and record.exc_info[1] is not None:
            e = record.exc_info[1]
            message += f": {type(e).__name__}: {' '.join(str(e).split())}"
            if message.startswith("Error handling request"):  # aiohttp: not HTTP at all
                message = f"{getattr(e, 'code', 400)} bad HTTP{message[len('Error handling request'):]}"
        return f"gigascroll serve: {message}"[:1000]


def tls_context(cert: str, key: str) -> ssl.SSLContext:
    """A server context from PEM files; OSError / ssl.SSLError (an OSError) when they are
    missing, not regular files (a FIFO would block OpenSSL's read forever, a device never
    end: checked before they are opened) or do not hold a certificate and its key."""
    from ..room.assets import check_regular
    for path, what in ((cert, "--tls-cert"), (key, "--tls-key")):
        st = check_regular(path, f"{what} {path}")
        if st.st_size > MAX_PEM_BYTES:
            raise OSError(f"{what} {path}: {st.st_size} bytes, not a PEM file (at most "
                          f"{MAX_PEM_BYTES})")
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    ctx.load_cert_chain(cert, key)
    return ctx


def _url(site_address, tls: bool) -> str:
    host, port = site_address[0], site_address[1]
    host = f"[{host}]" if ":" in host else host
    return f"{'https' if tls else 'http'}://{host}:{port}/"


def network_urls(url: str) -> list[str]:
    """For a URL on an unspecified address (0.0.0.0, ::): the same URL on each address this
    machine is reached by from its networks (the one a headset types), found from the
    routing table without sending a packet and from the host name; [] for any other URL."""
    scheme, _, rest = url.partition("://")
    host, _, port = rest.rstrip("/").rpartition(":")
    if host not in ("0.0.0.0", "[::]"):
        return []
    families = [(socket.AF_INET, "192.0.2.1")] + (  # documentation addresses: never reached
        [(socket.AF_INET6, "2001:db8::1")] if host == "[::]" else [])
    found: list[str] = []
    for family, probe in families:
        try:
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.connect((probe, 9))
                found.append(s.getsockname()[0])
        except OSError:
            pass  # no route of this family
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, type=socket.SOCK_STREAM):
            if info[0] == socket.AF_INET or host == "[::]":
                found.append(info[4][0])
    except OSError:
        pass
    addresses = [a for a in dict.fromkeys(found)
                 if not a.startswith(("127.", "::1", "fe80:")) and a != "::"]
    return [f"{scheme}://{f'[{a}]' if ':' in a else a}:{port}/" for a in addresses]


def listen_socket(host: str, port: int) -> socket.socket:
    """A socket listening on host:port (0: a free port), made before anything slow (the
    bake) so that a taken port fails at once. OSError when the address is taken, unknown or
    unavailable."""
    try:
        family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
    except socket.gaierror as e:
        raise OSError(f"unknown host {host!r} ({e.strerror})") from None
    return socket.create_server((host, port), family=family, backlog=512)


async def start_site(app: web.Application, host: str, port: int,
                     ssl_context: ssl.SSLContext | None = None,
                     sock: socket.socket | None = None) -> tuple[web.AppRunner, str]:
    """Starts `app` on `sock`, else on host:port (0: a free port); (its runner, its URL).
    OSError when the address is taken or unavailable."""
    runner = web.AppRunner(app, access_log=None, handle_signals=False,
                           shutdown_timeout=SHUTDOWN_GRACE_S)
    await runner.setup()
    site = (web.SockSite(runner, sock, ssl_context=ssl_context) if sock is not None else
            web.TCPSite(runner, host, port, ssl_context=ssl_context, reuse_address=True))
    try:
        await site.start()
    except BaseException:
        await runner.cleanup()
        raise
    return runner, _url(runner.addresses[0], ssl_context is not None)


def serve_forever(app: web.Application, host: str, port: int,
                  ssl_context: ssl.SSLContext | None = None, announce=print,
                  sock: socket.socket | None = None) -> str:
    """Serves until SIGINT or SIGTERM (on `sock` when given, else on host:port); returns the
    signal's name. `announce(url)` is called once the socket listens."""
    async def main():
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        caught = []
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, lambda s=sig: (caught.append(s), stop.set()))
        runner, url = await start_site(app, host, port, ssl_context, sock)
        try:
            announce(url)
            await stop.wait()
        finally:
            await runner.cleanup()
        return signal.Signals(caught[0]).name

    return asyncio.run(main())


class ServerThread:
    """The app on a background thread's event loop: `with ServerThread(app) as url: ...` or
    start() -> URL and stop(). One start per object; stop() may be called from any thread,
    any number of times (the first stops, the others wait for it). ValueError for a bad port,
    a second start, or an app another ServerThread serves."""

    def __init__(self, app: web.Application, host: str = "127.0.0.1", port: int = 0,
                 ssl_context: ssl.SSLContext | None = None):
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise ValueError(f"port must be an integer in [0, 65535], got {port!r}")
        self.app, self.host, self.port, self.ssl_context = app, host, port, ssl_context
        self.url: str | None = None
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="serve", daemon=True)
        self._runner = None
        self._lock = threading.Lock()
        self._started = False

    def start(self) -> str:
        with self._lock:
            if self._started:
                raise ValueError("this ServerThread was started already (make a new one)")
            if self.app.frozen:
                raise ValueError("this application is served already (by another ServerThread "
                                 "or runner): make a new one with make_app")
            self._started = True
            self._thread.start()
            future = asyncio.run_coroutine_threadsafe(
                start_site(self.app, self.host, self.port, self.ssl_context), self._loop)
            try:
                self._runner, self.url = future.result(timeout=60)
            except BaseException:
                self._close_loop()
                raise
            return self.url

    def stop(self) -> None:
        with self._lock:
            if self._runner is not None:
                runner, self._runner = self._runner, None
                asyncio.run_coroutine_threadsafe(runner.cleanup(), self._loop).result(timeout=60)
            self._close_loop()

    def _close_loop(self) -> None:
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


def _bad_http_too(record: logging.LogRecord) -> bool:
    """aiohttp logs a request it cannot parse as HTTP at debug level when it is a
    connection's first (non-HTTP traffic): keep those too, so each bad request has its line."""
    return record.levelno >= logging.INFO or str(record.msg).startswith("Error handling request")


class EveryFewSeconds(logging.Filter):
    """Lets a record through at most once every `seconds` per message start (its first 40
    characters): asyncio logs 'socket.accept() out of system resource' with a traceback at
    every retry while the process has no file descriptor left, thousands a minute."""

    def __init__(self, seconds: float = 10.0):
        super().__init__()
        self.seconds, self.last = seconds, {}

    def filter(self, record: logging.LogRecord) -> bool:
        key, now = str(record.msg)[:40], time.monotonic()
        if now - self.last.get(key, -1e300) < self.seconds:
            return False
        self.last[key] = now
        return True


def raise_open_files_limit() -> int:
    """Raises the soft limit on open files to the hard one (at most 65536) so that many
    visitors' connections fit; returns the limit now in force."""
    import resource
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    want = min(hard if hard != resource.RLIM_INFINITY else 65536, 65536)
    if soft == resource.RLIM_INFINITY or soft >= want:
        return soft
    try:
        resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))
        return want
    except (ValueError, OSError):
        return soft


def log_to_stderr(level: int = logging.INFO) -> None:
    """One-line records of the server's, aiohttp's and asyncio's loggers on stderr (asyncio's
    at most once every 10 s per message: EveryFewSeconds)."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(OneLineFormatter())
    asyncio_logger = logging.getLogger("asyncio")
    if not any(isinstance(f, EveryFewSeconds) for f in asyncio_logger.filters):
        asyncio_logger.addFilter(EveryFewSeconds())
    for name in ("gigascroll.serve", "aiohttp", "asyncio"):
        logger = logging.getLogger(name)
        logger.handlers[:] = [handler]
        logger.setLevel(level)
        logger.propagate = False
    server = logging.getLogger("aiohttp.server")
    server.setLevel(min(level, logging.DEBUG))
    server.addFilter(_bad_http_too)

"""Running shard builds on Dask with every wait bounded and named: connecting to a scheduler
(a TCP connection, then Dask's handshake, which distributed itself waits for without end),
its first worker, and workers that all vanish mid-build. Each ends, after `timeout` seconds,
in one OSError line naming the address and what it waited for; an address Dask cannot be
reached at this way (tls://, ucx://) or a peer that is not a Dask scheduler (an HTTP server,
whose answer Dask would read as a 3 EiB frame) also end in one line. Dask's own log lines
(a failed task's five-line block with its traceback) are silenced: the build reports the
task's error itself."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import os
import threading
import time
from typing import Callable
from urllib.parse import urlsplit

__all__ = ["CONNECT_TIMEOUT", "WORKER_TIMEOUT", "check_timeout", "run_on_dask",
           "scheduler_location"]

CONNECT_TIMEOUT = 30.0  # seconds for the connection and Dask's handshake (default)
WORKER_TIMEOUT = 60.0   # seconds for the first worker, or for one after all were lost
MAX_TIMEOUT = 7 * 86400.0
_POLL = 0.05            # seconds between looks at the cluster while no task finishes


def check_timeout(timeout) -> float | None:
    """None (the defaults) or a finite number of seconds in (0, one week]; ValueError if not."""
    if timeout is None:
        return None
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or \
            not (math.isfinite(timeout) and 0 < timeout <= MAX_TIMEOUT):
        raise ValueError(f"timeout must be a number of seconds in (0, {MAX_TIMEOUT:g}], "
                         f"got {timeout!r}")
    return float(timeout)


def scheduler_location(scheduler) -> tuple[str, int]:
    """(host, port) of a tcp://HOST:PORT address; ValueError naming what is wrong."""
    if not isinstance(scheduler, str) or "://" not in scheduler:
        raise ValueError(f"scheduler must be an address like tcp://HOST:PORT, got {scheduler!r}")
    scheme = scheduler.split("://", 1)[0].lower()
    if scheme != "tcp":
        why = {"tls": " (it needs certificates, which gigascroll does not configure)",
               "ucx": " (it needs the UCX library)"}.get(scheme, "")
        raise ValueError(f"scheduler address {scheduler}: {scheme}:// is not supported{why}; "
                         "use tcp://HOST:PORT")
    try:
        parts = urlsplit(scheduler)
        port = parts.port
    except ValueError as e:
        raise ValueError(f"scheduler address {scheduler}: {e}") from None
    if not parts.hostname or not port or parts.path not in ("", "/") or parts.query \
            or parts.fragment or parts.username or parts.password:
        raise ValueError(f"scheduler must be an address like tcp://HOST:PORT, got {scheduler!r}")
    return parts.hostname, port


def _handshake(address: str, timeout: float) -> dict:
    """Dask's handshake with the peer at `address` (distributed's own connect, bounded):
    its handshake record; OSError naming the address and what failed."""
    from distributed.comm import connect

    async def talk():
        comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout)
        try:
            return dict(comm.remote_info)
        finally:
            comm.abort()

    result: dict = {}

    def run():  # a loop of its own: the caller may be inside one (a notebook)
        try:
            result["info"] = asyncio.run(talk())
        except BaseException as e:  # handed to the caller
            result["error"] = e

    t = threading.Thread(target=run, name="gigascroll-dask-handshake", daemon=True)
    t.start()
    t.join(timeout + 5)
    error = result.get("error")
    if t.is_alive() or isinstance(error, asyncio.TimeoutError):
        raise OSError(f"{address} accepted the connection but sent no Dask handshake within "
                      f"{timeout:g} s (not a Dask scheduler, or a stuck one; --timeout)")
    if error is not None or not {"compression", "python"} <= set(result.get("info", {})):
        raise OSError(f"{address} is not a Dask scheduler (it does not answer in Dask's "
                      "protocol)")
    return result["info"]


def _first_bytes(sock, timeout: float) -> bytes | None:
    """What the peer sends first (up to 64 bytes, at least 8 unless it closes), within
    `timeout`: a Dask server sends its handshake unprompted, at once; a peer still silent
    after a second (or half the timeout) is sent an HTTP request, which an HTTP server
    answers (Dask's own handshake may hold no line end, so an HTTP server would wait for it
    forever). None if it stays silent."""
    import select
    deadline = time.monotonic() + timeout
    prompted, got = False, b""
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return got or None
        wait = left if prompted or got else min(left, timeout / 2, 1.0)
        if select.select([sock], [], [], wait)[0]:
            try:
                chunk = sock.recv(64 - len(got))
            except OSError:
                chunk = b""
            got += chunk
            if not chunk or len(got) >= 8:
                return got
        elif not prompted and not got:
            prompted = True
            with contextlib.suppress(OSError):
                sock.sendall(b"GET / HTTP/1.0\r\n\r\n")


def _probe(scheduler: str, timeout: float) -> None:
    """OSError in one line unless a TCP connection to the scheduler opens and the peer's
    first bytes look like Dask's handshake (a small length-prefixed frame), within
    `timeout` seconds each."""
    import socket
    import struct
    host, port = scheduler_location(scheduler)
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except socket.timeout:
        raise OSError(f"cannot reach the Dask scheduler at {scheduler}: no connection within "
                      f"{timeout:g} s (--timeout)") from None
    except OSError as e:
        raise OSError(f"cannot reach the Dask scheduler at {scheduler}: "
                      f"{e.strerror or e}") from None
    with sock:
        first = _first_bytes(sock, timeout)
    if first is None:
        raise OSError(f"{scheduler} accepted the connection but sent nothing within "
                      f"{timeout:g} s (not a Dask scheduler, or a stuck one; --timeout)")
    if first == b"":
        raise OSError(f"{scheduler} closed the connection without a Dask handshake: it is "
                      "not a Dask scheduler")
    if first.startswith(b"HTTP/"):
        raise OSError(f"{scheduler} is not a Dask scheduler (it answers HTTP: a dashboard "
                      "or web server?)")
    if len(first) < 8 or not 0 < struct.unpack("<Q", first[:8])[0] <= 1 << 20:
        raise OSError(f"{scheduler} is not a Dask scheduler (its first bytes are not a Dask "
                      "handshake)")


def _connect(scheduler: str, timeout: float):
    """A Client of the scheduler, every step bounded by `timeout`: our own probe, Dask's
    handshake (which distributed waits for without end), then the Client."""
    from dask.distributed import Client
    _probe(scheduler, timeout)
    _handshake(scheduler, timeout)
    try:
        return Client(scheduler, timeout=f"{timeout}s")
    except (OSError, TimeoutError) as e:
        raise OSError(f"cannot connect to the Dask scheduler at {scheduler}: "
                      f"{str(e).splitlines()[0][:200] if str(e) else type(e).__name__}") from None


@contextlib.contextmanager
def quiet_dask():
    """distributed's loggers silenced in this process while a build uses the cluster."""
    logger = logging.getLogger("distributed")
    old = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(old)


def _drop_unstarted_clusters() -> None:
    """A LocalCluster whose start was interrupted stays registered with distributed, whose exit
    hook then fails on it with a traceback (AssertionError: Status.init), and its nannies' start
    task ends in 'Task exception was never retrieved': close it here, quietly, unregister it,
    and keep asyncio's logger quiet for the rest of this (ending) process."""
    from distributed.deploy.spec import SpecCluster
    logging.getLogger("asyncio").setLevel(logging.CRITICAL + 1)
    for cluster in list(SpecCluster._instances):
        try:
            cluster.close(timeout=10)
        except BaseException:  # noqa: BLE001 - half started: whatever its close says
            pass
        SpecCluster._instances.discard(cluster)


def _await_workers(client, where: str, timeout: float) -> None:
    try:
        client.wait_for_workers(1, timeout=timeout)
    except (TimeoutError, asyncio.TimeoutError):
        raise OSError(f"{where} has no workers: none arrived within {timeout:g} s "
                      "(--timeout)") from None


def _gather(client, futures: dict, on_done, where: str, timeout: float) -> None:
    """Hands each finished shard's record to on_done as they finish (as_completed: O(1) per
    shard, for the 2^16 a pack may hold); OSError when the cluster has had no worker for
    `timeout` seconds or the client lost its scheduler."""
    from distributed import as_completed
    done = as_completed(futures, with_results=True)
    idle_since = None
    while not done.is_empty():
        if done.has_ready():
            fut, record = next(done)  # raises the task's error
            on_done(futures.pop(fut), record)
            fut.release()  # a lost worker must not make the cluster recompute it
            continue
        if client.status not in ("running", "connecting"):
            raise OSError(f"lost the connection to {where}")
        if client.scheduler_info().get("workers"):
            idle_since = None
        elif idle_since is None:
            idle_since = time.monotonic()
        elif time.monotonic() - idle_since > timeout:
            raise OSError(f"{where} has had no workers for {timeout:g} s (--timeout); "
                          f"{len(futures)} shard(s) wait")
        time.sleep(_POLL)


def run_on_dask(build_shard: Callable, tasks, workers: int, scheduler: str | None, on_done,
                local_cluster: Callable, timeout: float | None = None,
                on_ready: Callable[[], None] | None = None) -> None:
    """Runs build_shard(*args) for every (i, args) of `tasks` on the scheduler's workers
    (or on a LocalCluster of `workers` made by local_cluster) and hands each result to
    on_done(i, record) as it arrives; on_ready() runs once a worker is there. `timeout`:
    seconds for each wait (None: connecting CONNECT_TIMEOUT, workers WORKER_TIMEOUT)."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise ValueError("sharded builds on Dask need dask.distributed "
                         "(pip install 'gigascroll[cluster]')") from None
    connect_s = timeout or CONNECT_TIMEOUT
    workers_s = timeout or WORKER_TIMEOUT
    cluster = None
    with quiet_dask():
        if scheduler is not None:
            client, where = _connect(scheduler, connect_s), f"the Dask scheduler at {scheduler}"
        else:
            try:
                cluster = local_cluster(workers)
            except BaseException:  # SIGTERM or Ctrl-C while the workers start
                _drop_unstarted_clusters()
                raise
            client, where = Client(cluster), "the local Dask cluster"
        try:
            _await_workers(client, where, workers_s)
            if on_ready is not None:
                on_ready()
            futures = {client.submit(build_shard, *args, key=f"gigascroll-shard-{i}-{os.getpid()}",
                                     pure=False): i for i, args in tasks}
            try:
                _gather(client, futures, on_done, where, workers_s)
            finally:
                client.cancel(list(futures))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()

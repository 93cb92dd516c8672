"""No hang on Dask or on a resumed shard directory (issue 43, family 3): `gigascroll pack
--scheduler` to a loopback port that accepts and stays silent, to an HTTP server, to a
scheduler without workers, to a refused port and to tls:// and ucx:// addresses, and
`--resume` over a shard directory whose files are FIFOs, links to /dev/zero or directories,
each end with exit 2 and one line naming the address (or file) and what was waited for,
within the --timeout given. A task failing on a worker prints only the build's own error,
not Dask's worker log block. The subprocess timeouts are generous: only "it returned" is
asserted of time."""

from __future__ import annotations

import http.server
import os
import socket
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest
from PIL import Image

from gigascroll.pack.cluster import check_timeout, scheduler_location

distributed = pytest.importorskip("dask.distributed")

TIMEOUT = 2  # the --timeout the commands get (seconds)


def pack(*args, cwd=None) -> subprocess.CompletedProcess:
    """`gigascroll pack ARGS` in a subprocess; a hang fails the test (subprocess timeout)."""
    return subprocess.run([sys.executable, "-m", "gigascroll", "pack", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=240)


def one_line(r: subprocess.CompletedProcess, *fragments: str) -> str:
    """Asserts exit 2 and exactly one stderr line, holding every fragment; returns it."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr[-2000:]
    assert len(lines) == 1, r.stderr[-2000:]
    assert lines[0].startswith("gigascroll pack: error: "), lines
    for f in fragments:
        assert f in lines[0], (f, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    path = tmp_path_factory.mktemp("img") / "a.png"
    Image.fromarray(np.random.default_rng(3).integers(0, 256, (20, 30, 3), np.uint8)).save(path)
    return path


class SilentListener:
    """A loopback TCP port that accepts connections and never sends a byte (nor reads one)."""

    def __init__(self):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.accepted: list[socket.socket] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._accept, daemon=True)
        self.thread.start()

    def _accept(self):
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
                self.accepted.append(conn)
            except OSError:  # the 0.2 s poll, or the socket closed
                continue

    def close(self):
        self.stop.set()
        self.thread.join(5)
        for c in self.accepted:
            c.close()
        self.sock.close()


@pytest.fixture
def silent_port():
    listener = SilentListener()
    yield listener
    listener.close()


@pytest.fixture
def http_port():
    """A tiny HTTP server on loopback (answers every GET with 200)."""
    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.end_headers()
            self.wfile.write(b"hello\n")

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server.server_address[1]
    server.shutdown()
    server.server_close()
    thread.join(5)


def test_a_silent_port_ends_in_one_line(image, tmp_path, silent_port):
    address = f"tcp://127.0.0.1:{silent_port.port}"
    r = pack(image, "-o", tmp_path / "o.pack", "--scheduler", address, "--timeout", TIMEOUT)
    one_line(r, address, f"sent nothing within {TIMEOUT} s")
    assert silent_port.accepted, "the command never connected"
    assert not (tmp_path / "o.pack").exists()


def test_an_http_server_is_not_a_dask_scheduler(image, tmp_path, http_port):
    address = f"tcp://127.0.0.1:{http_port}"  # asked after 1 s of silence, it answers at once
    r = pack(image, "-o", tmp_path / "o.pack", "--scheduler", address, "--timeout", 20)
    one_line(r, address, "is not a Dask scheduler")


def test_a_refused_port_ends_in_one_line(image, tmp_path):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # bound once, now nobody listens
    r = pack(image, "-o", tmp_path / "o.pack", "--scheduler", f"tcp://127.0.0.1:{port}",
             "--timeout", TIMEOUT)
    one_line(r, f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}")


@pytest.mark.parametrize("address, says", [
    ("tls://127.0.0.1:8786", "tls:// is not supported"),
    ("ucx://127.0.0.1:8786", "ucx:// is not supported"),
    ("ws://127.0.0.1:8786", "ws:// is not supported"),
    ("tcp://127.0.0.1", "tcp://HOST:PORT"),
    ("tcp://127.0.0.1:99999", "out of range"),
    ("tcp://127.0.0.1:8786/x", "tcp://HOST:PORT"),
    ("127.0.0.1:8786", "tcp://HOST:PORT"),
])
def test_unsupported_addresses_end_in_one_line(image, tmp_path, address, says):
    r = pack(image, "-o", tmp_path / "o.pack", "--scheduler", address)
    one_line(r, says)


@pytest.mark.parametrize("value", ["nan", "inf", "0", "-1", "1e9"])
def test_bad_timeouts_are_refused(image, tmp_path, value):
    r = pack(image, "-o", tmp_path / "o.pack", "--workers", "1", "--timeout", value)
    one_line(r, "timeout")


def test_timeout_and_address_checks():
    assert check_timeout(None) is None and check_timeout(3) == 3.0
    for bad in (float("nan"), float("inf"), 0, -1, True, "3", 1e9):
        with pytest.raises(ValueError, match="timeout"):
            check_timeout(bad)
    assert scheduler_location("tcp://[::1]:8786") == ("::1", 8786)
    assert scheduler_location("TCP://example.org:1") == ("example.org", 1)
    for bad in (None, 8786, "tcp://:8786", "tcp://h:0x10", "tcp://u@h:1"):
        with pytest.raises(ValueError, match="scheduler"):
            scheduler_location(bad)


def test_a_scheduler_without_workers_ends_in_one_line(image, tmp_path):
    """A real Dask scheduler (in this process, threads only) that never gets a worker."""
    from dask.distributed import LocalCluster
    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1",
                      dashboard_address=":0") as cluster:
        address = cluster.scheduler_address
        # Connecting must succeed within the timeout on a loaded machine too: 5 s.
        r = pack(image, "-o", tmp_path / "o.pack", "--scheduler", address, "--timeout", 5)
    one_line(r, address, "has no workers", "within 5 s")


# ----------------------------------------------------------------------------- resume

@pytest.fixture(scope="module")
def shard_dir(tmp_path_factory):
    """A shard directory a failed sharded build left: painting 0 complete, painting 1 (a
    truncated PNG whose header reads) failed on the worker. Returns (inputs, out)."""
    root = tmp_path_factory.mktemp("resume")
    rng = np.random.default_rng(8)
    good, bad = root / "a.png", root / "b.png"
    Image.fromarray(rng.integers(0, 256, (40, 50, 3), np.uint8)).save(good)
    Image.fromarray(rng.integers(0, 256, (300, 300, 3), np.uint8)).save(bad)
    data = bad.read_bytes()
    bad.write_bytes(data[:len(data) // 3])
    from gigascroll import build_pack
    out = root / "o.pack"
    with pytest.raises(OSError, match="corrupt or truncated"):
        build_pack([good, bad], out, tile_size=16, border=2, workers=1, executor="processes")
    assert (root / "o.pack.shards" / "shard-00000.json").exists()
    return [good, bad], out


@pytest.mark.parametrize("name, make, kind", [
    ("tiles-00000.bin", lambda p: os.mkfifo(p), "a FIFO"),
    ("tiles-00000.bin", lambda p: os.symlink("/dev/zero", p), "a device (through a symbolic link)"),
    ("shard-00000.idx", lambda p: os.symlink("/dev/zero", p), "a device"),
    ("shard-00000.json", lambda p: os.mkfifo(p), "a FIFO"),
    ("shard-00000.idx", lambda p: os.mkdir(p), "a directory"),
])
def test_resume_refuses_fifos_and_devices_in_the_shard_dir(shard_dir, name, make, kind):
    inputs, out = shard_dir
    shards = out.parent / "o.pack.shards"  # its mark names `out`: used in place, then restored
    kept = shards / (name + ".kept")
    os.rename(shards / name, kept)
    make(shards / name)
    try:
        r = pack(*inputs, "-o", out, "--tile-size", 16, "--border", 2, "--workers", 1,
                 "--resume", "--timeout", TIMEOUT)
        one_line(r, name, kind, "not a regular file")
        assert os.path.lexists(shards / name)  # refused: nothing of it read or removed
        assert not out.exists()
    finally:
        if os.path.isdir(shards / name) and not os.path.islink(shards / name):
            os.rmdir(shards / name)
        else:
            os.unlink(shards / name)
        os.rename(kept, shards / name)


# ----------------------------------------------------------------------------- worker errors

FAILING_BUILD = textwrap.dedent("""
    import sys
    import numpy as np
    from gigascroll import build_pack

    def hook(index, name):
        if index == 1:
            raise ValueError(f"painting {name} is unreadable")

    if __name__ == "__main__":
        images = [np.zeros((20, 30, 3), np.uint8), np.ones((20, 30, 3), np.uint8)]
        try:
            build_pack(images, sys.argv[1], tile_size=16, border=2, workers=1,
                       shard_hook=hook, timeout=60)
        except ValueError as e:
            print("error:", e, file=sys.stderr)
            sys.exit(2)
""")


def test_a_failing_task_prints_no_dask_worker_block(tmp_path):
    script = tmp_path / "failing_build.py"
    script.write_text(FAILING_BUILD)
    r = subprocess.run([sys.executable, str(script), str(tmp_path / "o.pack")],
                       capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert r.returncode == 2, r.stderr[-3000:]
    assert r.stderr.strip().splitlines() == ["error: painting painting1 is unreadable"], \
        r.stderr[-3000:]


class FakeClient:
    """What _gather looks at: the client's status and the scheduler's worker list."""

    def __init__(self, status="running", workers=None):
        self.status = status
        self.workers = workers or {}

    def scheduler_info(self):
        return {"workers": self.workers}


class NeverDone:
    """as_completed over tasks that never finish."""

    def __init__(self, futures, with_results=True):
        pass

    def is_empty(self):
        return False

    def has_ready(self):
        return False


def test_tasks_waiting_on_a_cluster_without_workers_end_in_one_line(monkeypatch):
    """All workers gone mid-build: the tasks would wait forever; after `timeout` seconds
    without a worker the build ends naming the scheduler (a stand-in client, and tasks that
    never finish)."""
    import distributed

    from gigascroll.pack import cluster

    monkeypatch.setattr(distributed, "as_completed", NeverDone)
    monkeypatch.setattr(cluster, "_POLL", 0.01)
    where = "the Dask scheduler at tcp://127.0.0.1:1"
    with pytest.raises(OSError, match="has had no workers for 0.3 s.*2 shard"):
        cluster._gather(FakeClient(), {"f1": 0, "f2": 1}, None, where, 0.3)
    with pytest.raises(OSError, match="lost the connection to the Dask scheduler"):
        cluster._gather(FakeClient(status="closed"), {"f1": 0}, None, where, 0.3)
    # With a worker present the wait goes on (here: until the stand-in loses its scheduler).
    client = FakeClient(workers={"tcp://w": {}})
    looks = []

    def scheduler_info():
        looks.append(1)
        if len(looks) > 20:
            client.status = "closed"
        return {"workers": client.workers}

    client.scheduler_info = scheduler_info
    with pytest.raises(OSError, match="lost the connection"):
        cluster._gather(client, {"f1": 0}, None, where, 0.01)
    assert len(looks) > 20  # never "no workers" while one is there

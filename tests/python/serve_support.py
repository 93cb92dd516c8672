"""Helpers of the `gigascroll serve` tests: the server as a subprocess (its stdout's URL line,
its stderr kept in a file, its memory from /proc), raw HTTP requests and a self-signed TLS
certificate from the openssl command line."""

from __future__ import annotations

import json
import os
import select
import signal
import socket
import ssl
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path


class ServeProcess:
    """`python -m gigascroll serve ARGS` until stop(): url, pid, stderr()."""

    def __init__(self, args, workdir: Path, timeout: float = 120, env=None):
        self.err_path = Path(workdir) / f"serve-{time.monotonic_ns()}.err"
        self._err = open(self.err_path, "wb")
        self.proc = subprocess.Popen([sys.executable, "-m", "gigascroll", "serve", *map(str, args)],
                                     stdout=subprocess.PIPE, stderr=self._err,
                                     env=dict(os.environ, **(env or {})))
        self.url = self._wait_for_url(timeout)
        self.pid = self.proc.pid

    def _wait_for_url(self, timeout: float) -> str | None:
        deadline, line = time.monotonic() + timeout, b""
        while time.monotonic() < deadline:
            ready, _, _ = select.select([self.proc.stdout], [], [], 0.2)
            if ready:
                chunk = os.read(self.proc.stdout.fileno(), 4096)
                if not chunk:
                    return None
                line += chunk
                for text in line.decode(errors="replace").splitlines():
                    if text.startswith("serving "):
                        return text.split()[1].rstrip("/")
            elif self.proc.poll() is not None:
                return None
        raise TimeoutError(f"no URL from the server within {timeout} s: {self.stderr()}")

    def stderr(self) -> str:
        if not self._err.closed:
            self._err.flush()
        return self.err_path.read_text(errors="replace")

    def rss_kib(self) -> int:
        for line in Path(f"/proc/{self.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        raise RuntimeError("no VmRSS")

    def stop(self, sig=signal.SIGTERM, timeout: float = 30) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait()
        self._err.close()
        self.proc.stdout.close()
        return code

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
        return False


def raw_request(url: str, request: bytes, timeout: float = 10) -> tuple[int | None, bytes]:
    """Sends request bytes as they are to the server at url; (status or None, response)."""
    u = urllib.parse.urlsplit(url)
    with socket.create_connection((u.hostname, u.port), timeout=timeout) as s:
        s.sendall(request)
        data = b""
        try:
            while chunk := s.recv(65536):
                data += chunk
        except (ConnectionResetError, socket.timeout):
            pass
    if not data.startswith(b"HTTP/1."):
        return None, data
    return int(data.split(b" ", 2)[1]), data


def get_request(path: bytes, method: bytes = b"GET", body: bytes = b"", headers=b"") -> bytes:
    return (method + b" " + path + b" HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n"
            + headers + f"Content-Length: {len(body)}\r\n\r\n".encode() + body)


def self_signed(workdir: Path) -> tuple[Path, Path]:
    """(certificate, key) PEM files for 127.0.0.1 and localhost, made by openssl."""
    cert, key = Path(workdir) / "cert.pem", Path(workdir) / "key.pem"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", str(key),
                    "-out", str(cert), "-days", "2", "-subj", "/CN=localhost",
                    "-addext", "subjectAltName=IP:127.0.0.1,DNS:localhost"],
                   check=True, capture_output=True, timeout=60)
    return cert, key


def client_context(cert: Path) -> ssl.SSLContext:
    return ssl.create_default_context(cafile=str(cert))


def scene_of(url: str, context=None) -> dict:
    import urllib.request
    with urllib.request.urlopen(url + "/api/scene.json", timeout=30, context=context) as r:
        return json.load(r)


__all__ = ["ServeProcess", "raw_request", "get_request", "self_signed", "client_context",
           "scene_of", "signal"]

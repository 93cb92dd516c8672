"""Shared helpers of the fuzz suite (tests/python/test_fuzz_*.py).

Every fuzz case runs in a forked child of one long-lived worker process (a fork server that
has imported gigascroll once but never run it, so forking it is safe and costs milliseconds).
The parent therefore sees what a user would: the exit status (a signal shows as a negative
status), stdout and stderr, and a case that runs too long is killed and reported as a hang.
A child's address space is capped (RLIMIT_AS) so an unbounded allocation fails instead of
exhausting the machine.

Run lengths: the default run tries a bounded number of examples per family (the whole suite
stays within about two minutes); `make fuzz` sets GIGASCROLL_FUZZ=1, which runs the tests
marked `fuzz` with many more (GIGASCROLL_FUZZ_EXAMPLES=N sets their count)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from dataclasses import dataclass

import pytest
from hypothesis import HealthCheck, settings

LONG = os.environ.get("GIGASCROLL_FUZZ", "") not in ("", "0")
long_only = pytest.mark.skipif(not LONG, reason="long fuzz run: `make fuzz` (GIGASCROLL_FUZZ=1)")


def fuzz_settings(examples: int, long_examples: int | None = None, long: bool = False):
    """Hypothesis settings of a fuzz family: no deadline (cases fork and may build packs),
    a bounded number of examples (more for the long run)."""
    n = (long_examples or 20 * examples) if long else examples
    if long and os.environ.get("GIGASCROLL_FUZZ_EXAMPLES"):  # e.g. a shorter long run
        n = int(os.environ["GIGASCROLL_FUZZ_EXAMPLES"])
    return settings(max_examples=n, deadline=None, derandomize=not long,
                    suppress_health_check=list(HealthCheck), database=None)


# The family -> number of cases tried in this process (reported by the tests' summary).
CASES: dict[str, int] = {}


def count_case(family: str) -> None:
    CASES[family] = CASES.get(family, 0) + 1


# ----------------------------------------------------------------------------- the worker

_WORKER = r'''
import json, os, resource, signal, sys, time, traceback, io
import numpy as np
import gigascroll
from gigascroll import cli
# What the commands import lazily, imported once here (no thread is started by importing).
import OpenImageIO, tqdm, gigascroll.pack, gigascroll.views, gigascroll.export  # noqa: F401

def run_case(case):
    kind = case["kind"]
    if kind == "cli":
        return cli.main(case["argv"])
    if kind == "python":
        namespace = {"__name__": "fuzz_case"}
        exec(compile(case["code"], "<fuzz case>", "exec"), namespace)
        return 0
    raise SystemExit(f"unknown case kind {kind}")

def child(case, out_path, err_path):
    os.chdir(case["cwd"])
    out = os.open(out_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    err = os.open(err_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(out, 1)
    os.dup2(err, 2)
    limit = case.get("memory", 4 << 30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    sys.stdout = io.TextIOWrapper(os.fdopen(1, "wb", 0), write_through=True)
    sys.stderr = io.TextIOWrapper(os.fdopen(2, "wb", 0), write_through=True,
                                  errors="backslashreplace")
    try:
        rc = run_case(case)
        rc = 0 if rc is None else int(rc)
    except SystemExit as e:  # argparse: 2 for bad usage, 0 for --help
        rc = e.code if isinstance(e.code, int) else (0 if e.code is None else 2)
        if not isinstance(e.code, int) and e.code is not None:
            print(e.code, file=sys.stderr)
    except BaseException:
        traceback.print_exc()
        rc = 101  # a Python exception escaped: a traceback
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(rc)

def main():
    for line in sys.stdin:
        case = json.loads(line)
        out_path, err_path = case["out"], case["err"]
        pid = os.fork()
        if pid == 0:
            try:
                child(case, out_path, err_path)
            finally:
                os._exit(102)
        deadline = time.monotonic() + case.get("timeout", 60)
        status, timed_out = None, False
        while status is None:
            done, st = os.waitpid(pid, os.WNOHANG)
            if done:
                status = st
            elif time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                _, status = os.waitpid(pid, 0)
                timed_out = True
            else:
                time.sleep(0.005)
        code = os.waitstatus_to_exitcode(status)
        print(json.dumps({"code": code, "timeout": timed_out}), flush=True)

main()
'''


@dataclass
class Outcome:
    code: int          # exit code; -N: killed by signal N
    stdout: str
    stderr: str
    timeout: bool

    @property
    def traceback(self) -> bool:
        return "Traceback (most recent call last)" in self.stderr

    def describe(self) -> str:
        return (f"exit {self.code}{' (timeout)' if self.timeout else ''}\n--- stderr ---\n"
                f"{self.stderr[-3000:]}\n--- stdout ---\n{self.stdout[-1000:]}")


class Worker:
    """The fork server: `run(case)` runs one case in a fresh child and returns its Outcome."""

    def __init__(self, workdir):
        self.workdir = str(workdir)
        self._lock = threading.Lock()
        self._n = 0
        env = dict(os.environ, PYTHONFAULTHANDLER="1", TQDM_DISABLE="1")
        self._proc = subprocess.Popen([sys.executable, "-c", _WORKER], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, text=True, env=env)

    def run(self, case: dict, timeout: float = 60) -> Outcome:
        with self._lock:
            self._n += 1
            out = os.path.join(self.workdir, f"case-{self._n}.out")
            err = os.path.join(self.workdir, f"case-{self._n}.err")
            msg = dict(case, out=out, err=err, timeout=timeout)
            msg.setdefault("cwd", self.workdir)
            self._proc.stdin.write(json.dumps(msg) + "\n")
            self._proc.stdin.flush()
            reply = json.loads(self._proc.stdout.readline())
            with open(out, "rb") as f:
                stdout = f.read().decode("utf-8", "backslashreplace")
            with open(err, "rb") as f:
                stderr = f.read().decode("utf-8", "backslashreplace")
            os.unlink(out)
            os.unlink(err)
            return Outcome(reply["code"], stdout, stderr, reply["timeout"])

    def close(self) -> None:
        if self._proc.poll() is None:
            self._proc.stdin.close()
            self._proc.wait(timeout=30)


def cli_message_ok(o: Outcome) -> str | None:
    """None when a CLI outcome keeps the promise (exit 0, or exit 2 with one error line and
    no traceback); otherwise what is wrong."""
    if o.timeout:
        return "hang (killed after the timeout)"
    if o.code < 0:
        return f"killed by signal {-o.code}"
    if o.traceback:
        return "traceback"
    if o.code not in (0, 2):
        return f"exit code {o.code}"
    if o.code == 2:
        lines = [ln for ln in o.stderr.splitlines() if ln.strip() and "\r" not in ln]
        if not lines:
            return "exit 2 without a message"
        errors = [ln for ln in lines if ": error:" in ln]
        if len(errors) != 1:
            return f"exit 2 with {len(errors)} error lines"
        rest = lines[lines.index(errors[0]) + 1:]
        if rest:
            return "the error message spans several lines"
    return None


@pytest.fixture(scope="module")
def fork_worker(tmp_path_factory):
    w = Worker(tmp_path_factory.mktemp("fuzz-worker"))
    yield w
    w.close()

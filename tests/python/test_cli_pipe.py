"""A reader that leaves early (`gigascroll info --json PACK | head`) ends the command quietly with
status 141 (128 + SIGPIPE), as `cat` or `yes` end under a shell; a broken pipe that is not
standard output's stays an error. The reference for the quiet exit is what a Unix tool does:
seq (coreutils), killed by SIGPIPE, under the same closed pipe."""

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import gigascroll
from gigascroll import cli

QUIET = 128 + signal.SIGPIPE


@pytest.fixture(scope="module")
def many_paintings(tmp_path_factory):
    # 200 small paintings: the manifest JSON (about 170 KB) is far larger than a pipe's 64 KiB
    # buffer, so a reader that takes one line and leaves makes a write inside print fail.
    images = [np.full((40, 60, 3), i, np.uint8) for i in range(200)]
    return gigascroll.build_pack(images, tmp_path_factory.mktemp("pipe") / "many.pack").path


def run_into_closed_pipe(argv, env=None) -> tuple[int, str]:
    """Runs argv with stdout a pipe whose read end is closed before the child starts."""
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run(argv, stdout=w, stderr=subprocess.PIPE, timeout=120, env=env)
    finally:
        os.close(w)
    return p.returncode, p.stderr.decode(errors="replace")


def gigascroll_cmd(*args):
    return [sys.executable, "-m", "gigascroll", *args]


def test_unix_tool_reference():
    # The convention the CLI follows: a shell sees 128 + SIGPIPE for a tool killed by SIGPIPE.
    rc = subprocess.run(["bash", "-c", "seq 1 1000000 | head -n 1 >/dev/null; "
                         "exit ${PIPESTATUS[0]}"], timeout=60).returncode
    assert rc == QUIET


@pytest.mark.parametrize("args", [("info", "--json"), ("info",)])
def test_info_into_closed_pipe_is_quiet(many_paintings, args):
    code, err = run_into_closed_pipe(gigascroll_cmd(args[0], str(many_paintings), *args[1:]))
    assert code == QUIET
    assert err == "", err


def test_help_into_closed_pipe_is_quiet():
    # argparse ignores a failed write of its help and exits 0: quiet too.
    code, err = run_into_closed_pipe(gigascroll_cmd("--help"))
    assert code == 0 and err == "", err


def test_reader_leaves_after_one_line(many_paintings):
    # As `info --json PACK | head -n 1`, without the race of a shell pipeline: the reader takes
    # one line and closes while more than a pipe's buffer is still to be written.
    p = subprocess.Popen(gigascroll_cmd("info", "--json", str(many_paintings)),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert p.stdout.readline() == b"{\n"
    p.stdout.close()
    err = p.stderr.read().decode(errors="replace")
    assert p.wait(timeout=120) == QUIET
    assert err == "", err


def test_info_to_an_open_pipe_is_complete(many_paintings):
    p = subprocess.run(gigascroll_cmd("info", "--json", str(many_paintings)), capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0 and p.stderr == ""
    import json
    text = p.stdout
    assert len(text) > 2 * 65536 and len(json.loads(text)["paintings"]) == 200


def test_other_broken_pipe_is_an_error(monkeypatch, capsys):
    # A BrokenPipeError from another pipe (an encoder's stdin, a socket) is a failure.
    from gigascroll.commands import info

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(info, "run", broken)
    assert cli.main(["info", "whatever.pack"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gigascroll info: error:") and "Broken pipe" in err

import subprocess
import sys

import gigascroll
from gigascroll import cli


def test_core_module_loads():
    assert gigascroll.hardware_threads() >= 1


def test_cli_and_module_entry_point_agree():
    out_m = subprocess.run([sys.executable, "-m", "gigascroll", "--help"],
                           capture_output=True, text=True, check=True).stdout
    assert "COMMAND" in out_m
    assert cli.build_parser().format_help().split()[1:4] == out_m.split()[1:4]


def test_unknown_command_fails_cleanly():
    r = subprocess.run([sys.executable, "-m", "gigascroll", "no-such-command"],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert "invalid choice" in r.stderr

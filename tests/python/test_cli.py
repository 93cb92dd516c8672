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


def test_subsystems_export_distinct_names():
    # gigascroll/__init__ re-exports every subsystem with *: a name exported twice would
    # silently shadow another subsystem's class.
    from collections import Counter

    from gigascroll import pack, photon, runtime, views
    counts = Counter(n for m in (pack, runtime, views, photon) for n in m.__all__)
    assert [n for n, k in counts.items() if k > 1] == []
    for name in counts:
        assert hasattr(gigascroll, name), name

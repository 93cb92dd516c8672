"""Fuzz families for what issue 41's defects added: the painting argument of the pack readers'
per-tile methods (a painting object or its index, and anything else a user may pass), and
commands whose standard output's reader has gone. Each reader case runs in a forked child
(fuzz_support): it must end in ValueError, OSError or TypeError, never a crash or a hang."""

import os
import subprocess
import sys

import numpy as np
import pytest
from fuzz_support import count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gigascroll import build_pack

PAINTINGS = ["pk.paintings[0]", "pk.paintings[-1]", "other.paintings[0]", "pure.paintings[0]",
             "pk.paintings", "None", "-1", "0", "1", "2", "2**32", "2**64", "1.5", "float('nan')",
             "'0'", "True", "np.uint32(0)", "np.int64(-1)", "object()", "pk", "orphan",
             "gigascroll.TilePack(PACK).paintings[0]"]
INDICES = ["0", "1", "-1", "2**31", "2**63", "None", "0.5", "np.uint8(0)"]
METHODS = ["has_tile", "locate", "tile_file", "read_tile", "read_slot_tile", "read_tile_into"]

_CASE = """
import gc, numpy as np, gigascroll
from gigascroll.pack.reader import PurePack
PACK = {pack!r}
pk, other, pure = gigascroll.TilePack(PACK), gigascroll.TilePack(PACK), PurePack(PACK)
orphan = gigascroll.TilePack(PACK).paintings[1]   # its pack is kept alive by the painting
gc.collect()
out = np.empty((pk.tile_size, pk.tile_size, 3), np.uint8)
reader = {reader}
args = [{painting}, {level}, {tx}, {ty}] + ([out] if {method!r} == "read_tile_into" else [])
try:
    getattr(reader, {method!r})(*args)
except (ValueError, OSError, TypeError):
    pass
except AttributeError as e:  # the pure reader has no has_tile / read_tile_into
    if {method!r} not in ("has_tile", "read_slot_tile", "read_tile_into") or reader is not pure:
        raise
"""


@pytest.fixture(scope="module")
def two_paintings(tmp_path_factory):
    rng = np.random.default_rng(3)
    path = tmp_path_factory.mktemp("fuzz-painting") / "two.pack"
    build_pack([rng.integers(0, 256, (40, 70, 3), np.uint8), rng.integers(0, 256, (20, 20, 3),
                                                                            np.uint8)],
               path, tile_size=16, border=2)
    return str(path)


@fuzz_settings(40)
@given(method=st.sampled_from(METHODS), painting=st.sampled_from(PAINTINGS),
       level=st.sampled_from(INDICES), tx=st.sampled_from(INDICES), ty=st.sampled_from(INDICES),
       reader=st.sampled_from(["pk", "pure"]))
def test_fuzz_painting_argument(fork_worker, two_paintings, method, painting, level, tx, ty,
                                reader):
    count_case("painting-arg")
    code = _CASE.format(pack=two_paintings, reader=reader, painting=painting, level=level, tx=tx,
                        ty=ty, method=method)
    o = fork_worker.run({"kind": "python", "code": code, "memory": 2 << 30}, timeout=60)
    call = f"{reader}.{method}({painting}, {level}, {tx}, {ty})"
    assert not o.timeout, f"{call}: hang\n{o.describe()}"
    assert o.code == 0, f"{call}: {'signal ' + str(-o.code) if o.code < 0 else 'exception'}\n" \
                        f"{o.describe()}"


COMMANDS = [["info", "{pack}"], ["info", "--json", "{pack}"], ["info", "--verify", "{pack}"],
            ["info", "{missing}"], ["--help"], ["gallery", "--help"], ["pack", "--help"],
            ["info", "--json", "{garbage}"]]


@fuzz_settings(6)
@given(argv=st.sampled_from(COMMANDS))
def test_fuzz_closed_stdout(tmp_path_factory, two_paintings, argv):
    """Any command into a pipe with no reader: quiet (141, or argparse's 0) or its usual
    one-line error (2) on stderr; never a traceback or 'Broken pipe' as an error."""
    count_case("closed-stdout")
    d = tmp_path_factory.mktemp("closed-stdout")
    (d / "garbage").mkdir()
    (d / "garbage" / "manifest.json").write_text("{not json")
    args = [a.format(pack=two_paintings, missing=d / "none.pack", garbage=d / "garbage")
            for a in argv]
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run([sys.executable, "-m", "gigascroll", *args], stdout=w,
                           stderr=subprocess.PIPE, timeout=120)
    finally:
        os.close(w)
    err = p.stderr.decode(errors="replace")
    assert "Traceback" not in err and "Broken pipe" not in err, err
    assert p.returncode in (0, 2, 141), (args, p.returncode, err)
    if p.returncode in (0, 141):
        assert err == "", err
    else:
        assert len(err.strip().splitlines()) == 1, err

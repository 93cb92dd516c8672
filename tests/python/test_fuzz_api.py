"""Fuzz: random arguments for every public class and function in gigascroll.__all__. Each
call must return or raise a clear Python exception (ValueError, OSError, TypeError and the
package's own errors): never a crash, an abort, a hang or another exception type. Each case
runs in a forked child (fuzz_support.Worker) with its address space capped."""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from fuzz_support import CASES, count_case, fork_worker, fuzz_settings, long_only  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

import gigascroll
from gigascroll import build_pack

# Argument values as source text, materialised in the child. PACK: a small valid pack.
VALUES = [
    "0", "1", "3", "-1", "2**31", "2**61", "2**64", "-2**63", "True", "None",
    "float('nan')", "float('inf')", "-float('inf')", "1e308", "0.5", "1e-300",
    "''", "'x'", "'brkga'", "'shelf'", "'raw'", "'\\udcff'", "'a' * 10000",
    "np.zeros((0, 3))", "np.full((2, 3), np.nan)", "np.zeros((4, 4, 3), np.uint8)",
    "np.zeros((3,), np.float32)", "np.ones((2, 2, 2, 2))", "np.zeros((5, 7), np.uint16)",
    "np.array([1e300, -1e300, 0.0])", "np.zeros((2, 3), np.int64)",
    "PACK", "'/nonexistent/x'", "GARBAGE", "DEEP", "OUT",
    "[]", "[(1, 1)]", "[(3, 4)]", "[(2**40, 1)]", "[1, 2, 3]", "{}", "{'a': 1}",
    "(0.0, 0.0, 0.0)", "(1e30, 0.0, 0.0)", "(float('nan'), 0.0, 1.0)",
    # objects of the package itself, so calls get past the type checks
    "tp()", "scene()", "camera()", "exhibition()",
]
ALLOWED = (ValueError, OSError, TypeError)

# Names whose hostile inputs are another branch's to fix (C++-side bounds: Embree ray
# validation, core sizes, loader threads, photon counts), with why; their calls are kept out
# of the default family and listed in the report. Filled from the fuzz runs' findings.
OTHER_SCOPE: dict[str, str] = {}


def public_callables():
    out = []
    for name in gigascroll.__all__:
        obj = getattr(gigascroll, name)
        if callable(obj) and name not in OTHER_SCOPE:
            out.append(name)
    return sorted(out)


CALLABLES = public_callables()


def _arity(name: str) -> tuple[list[str], int]:
    """(parameter names, required count) when the signature is known, else ([], 0)."""
    try:
        sig = inspect.signature(getattr(gigascroll, name))
    except (TypeError, ValueError):
        return [], 0
    params = [p for p in sig.parameters.values() if p.kind in (p.POSITIONAL_ONLY,
                                                                 p.POSITIONAL_OR_KEYWORD,
                                                                 p.KEYWORD_ONLY)]
    required = sum(1 for p in params if p.default is p.empty and p.kind != p.KEYWORD_ONLY)
    return [p.name for p in params], required


@st.composite
def api_case(draw):
    name = draw(st.sampled_from(CALLABLES))
    names, required = _arity(name)
    n = draw(st.integers(0, max(4, required + 1)) if not names else
             st.integers(max(0, required - 1), min(len(names), required + 2)))
    args = [draw(st.sampled_from(VALUES)) for _ in range(n)]
    kwargs = {}
    if names and draw(st.booleans()):
        kw = draw(st.sampled_from(names))
        if names.index(kw) >= n:
            kwargs[kw] = draw(st.sampled_from(VALUES))
    return name, args, kwargs


_CALL = """
import re, numpy as np, gigascroll
PACK, GARBAGE, DEEP, OUT = {pack!r}, {garbage!r}, {deep!r}, {out!r}
ALLOWED = (ValueError, OSError, TypeError)
tp = lambda: gigascroll.TilePack(PACK)
scene = lambda: gigascroll.builtin_scene("cornell", (8, 8))[0]
camera = lambda: gigascroll.builtin_scene("cornell", (8, 8))[1]
exhibition = lambda: gigascroll.single_scroll()
args = [{args}]
kwargs = {{{kwargs}}}
try:
    result = gigascroll.{name}(*args, **kwargs)
    # Objects that were made: touch their repr and public read-only properties as a user would.
    repr(result)
except ALLOWED:
    pass
except AttributeError as e:
    # Duck typing: an argument of the wrong type (a plain value, or another gigascroll object,
    # where a gigascroll object belongs) is misuse by type, reported by Python itself as a
    # missing attribute of the argument; any other AttributeError is a bug.
    if not re.fullmatch(r"'[\\w.]+' object has no attribute '\\w+'", str(e)):
        raise
"""


def _run(fork_worker, tmp_path_factory, files, case, family):
    name, args, kwargs = case
    count_case(family)
    out = str(tmp_path_factory.mktemp("fuzz-api-out") / "o")
    code = _CALL.format(name=name, args=", ".join(args), out=out,
                        kwargs=", ".join(f"{k!r}: {v}" for k, v in kwargs.items()), **files)
    o = fork_worker.run({"kind": "python", "code": code, "memory": 4 << 30}, timeout=60)
    call = f"gigascroll.{name}({', '.join(args + [f'{k}={v}' for k, v in kwargs.items()])})"
    assert not o.timeout, f"{call}: hang\n{o.describe()}"
    assert o.code == 0, f"{call}: {'signal ' + str(-o.code) if o.code < 0 else 'exception'}\n{o.describe()}"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz-api-files")
    img = np.random.default_rng(0).integers(0, 256, (20, 30, 3), np.uint8)
    build_pack(img, d / "pack", tile_size=16, border=2)
    (d / "garbage.bin").write_bytes(bytes(range(256)) * 3)
    (d / "deep.json").write_text("[" * 100000 + "]" * 100000)
    return {"pack": str(d / "pack"), "garbage": str(d / "garbage.bin"), "deep": str(d / "deep.json")}


def test_every_public_name_is_considered():
    assert set(CALLABLES) | set(OTHER_SCOPE) >= {n for n in gigascroll.__all__
                                                  if callable(getattr(gigascroll, n))}


@fuzz_settings(300)
@given(case=api_case())
def test_fuzz_api(fork_worker, tmp_path_factory, files, case):
    _run(fork_worker, tmp_path_factory, files, case, "api")


@pytest.mark.fuzz
@long_only
@fuzz_settings(300, long_examples=6000, long=True)
@given(case=api_case())
def test_fuzz_api_long(fork_worker, tmp_path_factory, files, case):
    _run(fork_worker, tmp_path_factory, files, case, "api-long")

"""Fuzzing tile packs (hypothesis): random mutations of a small valid version-2 pack's manifest
values, index bytes and tile bytes. Every outcome must be a success whose tiles are the right
ones (compared with the undamaged pack's) or a clean ValueError / OSError, from both the
core's reader (gigascroll.TilePack) and the pure-Python one (PurePack); and the two
manifest validators (core and Python) must accept and refuse the same manifests.

Opening and reading damaged packs runs in a worker subprocess, so a crash (a segfault, an
abort) or a hang fails the test with the case that caused it instead of killing pytest. The
default run tries a few hundred cases in about a minute; `pytest -m fuzz` runs many more."""

from __future__ import annotations

import copy
import json
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gigascroll import _core, build_pack
from gigascroll.pack.reader import parse_manifest_text

# (default run, `-m fuzz` run) examples per family
BUDGET = {"agree": (500, 5000), "manifest": (60, 600), "index": (60, 600), "tiles": (40, 400)}
COUNTS: dict[str, int] = {}

# The worker: opens a pack with both readers, reads every tile and compares it with the
# reference digests; answers one JSON line per request.
WORKER = textwrap.dedent("""
    import json, sys, warnings
    import xxhash
    warnings.simplefilter("ignore")
    from gigascroll import TilePack
    from gigascroll.pack.reader import PurePack
    ref = json.loads(sys.stdin.readline())
    print("ready", flush=True)
    for line in sys.stdin:
        path = json.loads(line)
        out = {}
        for name, cls in (("core", TilePack), ("pure", PurePack)):
            r = {"ok": 0, "wrong": [], "errors": {}}
            try:
                pack = cls(path)
                for key, digest in ref.items():
                    p, l, tx, ty = map(int, key.split(","))
                    try:
                        t = pack.read_tile(p, l, tx, ty)
                    except (ValueError, OSError) as e:
                        r["errors"][type(e).__name__] = r["errors"].get(type(e).__name__, 0) + 1
                        continue
                    if xxhash.xxh3_64_hexdigest(t.tobytes()) == digest:
                        r["ok"] += 1
                    else:
                        r["wrong"].append(key)
            except (ValueError, OSError) as e:
                r["open"] = type(e).__name__ + ": " + str(e)[:200]
            except Exception as e:  # anything else is a finding
                r["bad"] = type(e).__name__ + ": " + str(e)[:300]
            out[name] = r
        print(json.dumps(out), flush=True)
""")


class Worker:
    def __init__(self, reference: dict):
        self.reference = reference
        self.proc = None

    def start(self):
        self.proc = subprocess.Popen([sys.executable, "-c", WORKER], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)
        self.proc.stdin.write(json.dumps(self.reference) + "\n")
        self.proc.stdin.flush()
        assert self.proc.stdout.readline().strip() == "ready"

    def check(self, path, what: str) -> dict:
        """Both readers' outcome on the pack at path; fails on a crash, a hang, a wrong tile
        or an exception other than ValueError / OSError."""
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.proc.stdin.write(json.dumps(str(path)) + "\n")
        self.proc.stdin.flush()
        import select
        ready, _, _ = select.select([self.proc.stdout], [], [], 60)
        if not ready:
            self.proc.kill()
            self.proc = None
            pytest.fail(f"reading a pack with {what} hung for 60 s")
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.proc = None
            pytest.fail(f"the reader crashed (exit {code}) on a pack with {what}")
        out = json.loads(line)
        for name, r in out.items():
            assert "bad" not in r, f"{name} reader on {what}: {r['bad']}"
            assert not r["wrong"], f"{name} reader served wrong tiles {r['wrong'][:5]} ({what})"
        return out

    def close(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.stdin.close()
            self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A small valid v2 pack (two paintings, zstd) and the digest of every tile."""
    import xxhash
    rng = np.random.default_rng(3)
    a = rng.integers(0, 256, (40, 61, 3), dtype=np.uint8)
    a[10:20] = 77
    b = rng.integers(0, 256, (19, 23, 3), dtype=np.uint8)
    root = tmp_path_factory.mktemp("fuzz")
    pack = build_pack([a, b], root / "base", tile_size=16, border=2, codec="zstd")
    ref = {}
    for i, p in enumerate(pack.paintings):
        for l, (nx, ny) in enumerate(p.level_tiles):
            for ty in range(ny):
                for tx in range(nx):
                    ref[f"{i},{l},{tx},{ty}"] = xxhash.xxh3_64_hexdigest(
                        pack.read_tile(i, l, tx, ty).tobytes())
    manifest = json.loads((root / "base" / "manifest.json").read_text())
    return root, root / "base", manifest, ref


@pytest.fixture(scope="module")
def worker(base):
    w = Worker(base[3])
    yield w
    w.close()


@pytest.fixture(scope="module", autouse=True)
def report():
    yield
    print("\nfuzz cases tried: " + ", ".join(f"{k} {v}" for k, v in sorted(COUNTS.items())))


def _budget(request, family: str) -> int:
    return BUDGET[family][1 if request.node.get_closest_marker("fuzz") else 0]


def _count(family: str) -> None:
    COUNTS[family] = COUNTS.get(family, 0) + 1


# ----------------------------------------------------------------------------- strategies

HOSTILE_INTS = [0, 1, -1, 2, 3, 12, 2 ** 20, 2 ** 20 + 1, 2 ** 31, 2 ** 31 - 1, 2 ** 32,
                2 ** 32 + 16, 2 ** 53 + 1, 2 ** 63, 2 ** 64 - 1, 2 ** 64, -2 ** 63]
values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.sampled_from(HOSTILE_INTS),
              st.integers(-10, 5000), st.floats(allow_nan=False, allow_infinity=False),
              st.sampled_from([1.0, 16.0, 1.9, 2.0, 0.5, 1e300]),
              st.text(max_size=12), st.sampled_from(["raw", "zstd", "../x", "tiles-00000.bin"])),
    lambda children: st.one_of(st.lists(children, max_size=3),
                               st.dictionaries(st.text(max_size=6), children, max_size=3)),
    max_leaves=6)


def _paths(node, prefix=()):
    """Every path to a value in the JSON tree."""
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, prefix + (i,))


def _set(m, path, value, delete=False):
    node = m
    for k in path[:-1]:
        node = node[k]
    if delete and isinstance(node, dict):
        del node[path[-1]]
    elif delete and isinstance(node, list):
        node.pop(path[-1])
    else:
        node[path[-1]] = value


@st.composite
def manifest_mutations(draw, manifest):
    """1 to 3 random replacements / deletions / numeric nudges of a manifest's values."""
    m = copy.deepcopy(manifest)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(m) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        node = m
        for k in path:
            node = node[k]
        kind = draw(st.sampled_from(["replace", "delete", "nudge", "nudge", "retype"]))
        if kind == "retype" and isinstance(node, int) and not isinstance(node, bool):
            # the same value as another JSON type: 16 -> 16.0, "16", true
            _set(m, path, draw(st.sampled_from([float(node), str(node), bool(node)])))
        elif kind == "nudge" and isinstance(node, int) and not isinstance(node, bool):
            _set(m, path, node + draw(st.sampled_from([-1, 1, 2, node, 2 ** 32, -node])))
        elif kind == "delete":
            _set(m, path, None, delete=True)
        else:
            _set(m, path, draw(values))
    return m


def _agreement(m) -> None:
    text = json.dumps(m)
    try:
        _core.check_manifest(text)
        core_ok, core_why = True, ""
    except ValueError as e:
        core_ok, core_why = False, str(e)
    try:
        parse_manifest_text(text)
        pure_ok, pure_why = True, ""
    except OSError as e:
        pure_ok, pure_why = False, str(e)
    assert core_ok == pure_ok, (f"core {'accepts' if core_ok else 'refuses: ' + core_why}; "
                                f"pure {'accepts' if pure_ok else 'refuses: ' + pure_why}")


# ----------------------------------------------------------------------------- families

def _run(family, request, strategy, body):
    """Runs body over `strategy` with this family's budget (hypothesis, no deadline)."""
    @settings(max_examples=_budget(request, family), deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(strategy)
    def run(case):
        _count(family)
        body(case)
    run()


def _agree_family(request, base):
    _, _, manifest, _ = base
    # Everything must agree, the colour record's fields included.
    _run("agree", request, manifest_mutations(manifest), _agreement)


def _manifest_family(request, base, worker):
    root, good, manifest, _ = base
    case_dir = root / "case-manifest"

    def body(m):
        shutil.rmtree(case_dir, ignore_errors=True)
        shutil.copytree(good, case_dir)
        (case_dir / "manifest.json").write_text(json.dumps(m))
        worker.check(case_dir, f"manifest {json.dumps(m)[:300]}")

    _run("manifest", request, manifest_mutations(manifest), body)


@st.composite
def byte_mutations(draw, size: int, header: int = 32, entry: int = 0):
    """A list of (offset, new bytes) edits and a truncation length for a file of `size`."""
    edits = []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["byte", "u64", "u32", "u16", "header"]))
        if kind == "header":
            off = draw(st.integers(0, header - 1))
        else:
            off = draw(st.integers(0, max(0, size - 1)))
        if kind in ("u64", "u32", "u16") and entry:  # aligned to an entry's field
            base = header + (off - header) // entry * entry if off >= header else 0
            field = draw(st.sampled_from([(0, 8), (8, 4), (12, 2), (14, 2), (16, 8)]))
            off, width = base + field[0], field[1]
        else:
            width = {"byte": 1, "u64": 8, "u32": 4, "u16": 2, "header": 1}[kind]
        value = draw(st.one_of(st.integers(0, 2 ** (8 * width) - 1),
                               st.sampled_from([0, 1, 2 ** (8 * width) - 1, 2 ** (8 * width - 1)])))
        edits.append((off, value.to_bytes(width, "little")))
    truncate = draw(st.one_of(st.none(), st.integers(0, size)))
    return edits, truncate


def _apply(path, edits, truncate):
    data = bytearray(path.read_bytes())
    for off, b in edits:
        data[off:off + len(b)] = b[:max(0, len(data) - off)]
    if truncate is not None:
        del data[truncate:]
    path.write_bytes(bytes(data))


def _file_family(request, base, worker, family, name, entry):
    root, good, _, _ = base
    case_dir = root / f"case-{family}"
    size = (good / name).stat().st_size

    def body(case):
        edits, truncate = case
        shutil.rmtree(case_dir, ignore_errors=True)
        shutil.copytree(good, case_dir)
        _apply(case_dir / name, edits, truncate)
        worker.check(case_dir, f"{name} edits {edits[:4]} truncated to {truncate}")

    _run(family, request, byte_mutations(size, entry=entry), body)


def test_fuzz_validators_agree(request, base):
    _agree_family(request, base)


def test_fuzz_mutated_manifests(request, base, worker):
    _manifest_family(request, base, worker)


def test_fuzz_mutated_index(request, base, worker):
    _file_family(request, base, worker, "index", "index.bin", entry=24)


def test_fuzz_mutated_tiles(request, base, worker):
    _file_family(request, base, worker, "tiles", "tiles-00000.bin", entry=0)


@pytest.mark.fuzz
@pytest.mark.timeout(3600)
def test_fuzz_pack_long(request, base, worker):
    """The long run of every family (pytest -m fuzz)."""
    _agree_family(request, base)
    _manifest_family(request, base, worker)
    _file_family(request, base, worker, "index", "index.bin", entry=24)
    _file_family(request, base, worker, "tiles", "tiles-00000.bin", entry=0)


def test_worker_catches_a_crash(base, tmp_path):
    """The harness itself: a reader process that dies is reported, not survived silently."""
    w = Worker({"0,0,0,0": "0"})
    w.start()
    os.kill(w.proc.pid, 9)
    w.proc.wait()
    w.start = lambda: None  # noqa: E731 - keep the dead process
    with pytest.raises(pytest.fail.Exception, match="crashed"):
        w.proc.stdin = open(os.devnull, "w")
        w.check(base[1], "a killed reader")

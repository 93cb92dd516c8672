"""Fuzzing the core's entry points (hypothesis): cameras, stereo cameras, rays, meshes and
size-like parameters, finite, non-finite and huge. Each case must end in a result or a clean
exception with a message (ValueError, OSError, MemoryError; TypeError or OverflowError when
an integer does not fit the argument's C type at all), never in a crash, an abort or a hang.

Cases run in a worker subprocess, so an abort (Embree's ray.valid() assertion, a GS_CHECK, a
segfault) fails the test with the case instead of killing pytest; a case taking longer than
CASE_TIMEOUT seconds counts as a hang. The default run tries a few hundred cases in ~30 s;
`pytest -m fuzz` runs ten times as many. The number of cases per family is printed at the
end of the module (pytest -s) and checked against the setting."""
import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

CASE_TIMEOUT = 60.0
CLEAN = ("ValueError", "OSError", "MemoryError", "TypeError", "OverflowError")

# The worker: reads one JSON case per line, runs it, answers one JSON line.
WORKER = textwrap.dedent(r'''
    import json, math, sys, traceback
    import numpy as np
    import gigascroll as g
    from gigascroll import _core

    def f(x):  # JSON carries non-finite floats as strings
        if isinstance(x, list):
            return [f(v) for v in x]
        return float(x) if isinstance(x, str) else x

    _scene = None
    def scene():
        global _scene
        if _scene is None:
            _scene = g.builtin_scene("cornell", resolution=(4, 4))[0]
        return _scene

    def run(c):
        k = c["kind"]
        if k == "camera":
            cam = g.Camera(f(c["position"]), f(c["look_at"]), f(c["up"]), f(c["fov"]),
                           resolution=tuple(c["resolution"]))
            if cam.width * cam.height <= 64:
                img = g.render(scene(), cam, photons=200, radius=0.05)
                assert np.isfinite(img).all()
            return "ok"
        if k == "camera_raw":
            cam = _core.Camera(f(c["position"]), f(c["forward"]), f(c["up"]), f(c["tx"]), f(c["ty"]),
                               c["width"], c["height"])
            if cam.width * cam.height <= 64:
                g.render(scene(), cam, photons=200, radius=0.05)
            return "ok"
        if k == "stereo":
            cam = g.Camera(f(c["position"]), [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 45.0, resolution=(4, 4))
            eyes = g.StereoCamera(cam, f(c["ipd"]))
            g.render_stereo(scene(), eyes, photons=200, radius=0.05)
            return "ok"
        if k == "ray":
            scene().intersect(f(c["o"]), f(c["d"]))
            return "ok"
        if k == "mesh":
            s = g.Scene()
            v = np.array(f(c["vertices"]), dtype=np.float64).reshape(-1, 3)
            s.add_mesh(v, np.array([[0, 1, 2]]), emission=(1.0, 1.0, 1.0))
            s.add_mesh(v[::-1].copy(), np.array([[0, 1, 2]]))
            s.commit()
            s.intersect(f(c["o"]), f(c["d"]))
            cam = g.Camera(f(c["o"]), [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 45.0, resolution=(3, 3))
            g.render(s, cam, photons=100, radius=0.1)
            return "ok"
        if k == "sizes":
            what = c["what"]
            n = c["n"]
            if what == "loader_threads":
                _core.TileLoader(pack(), "lockfree", n).close()
            elif what == "loader_queue":
                _core.TileLoader(pack(), "locked", 1, queue_capacity=n).close()
            elif what == "loader_pool":
                _core.TileLoader(pack(), "lockfree", 1, pool_tiles=n).close()
            elif what == "trace_count":
                _core._trace_photons(scene(), n, threads=1, max_stored=1 << 20)
            elif what == "trace_threads":
                _core._trace_photons(scene(), 64, threads=n)
            elif what == "render_threads":
                g.render(scene(), g.Camera([0, 0, 3.9], [0, 0, 0], [0, 1, 0], resolution=(2, 2)),
                         photons=64, threads=n)
            elif what == "render_spp":
                g.render(scene(), g.Camera([0, 0, 3.9], [0, 0, 0], [0, 1, 0], resolution=(1, 1)),
                         photons=64, spp=n)
            elif what == "render_photons":
                g.render(scene(), g.Camera([0, 0, 3.9], [0, 0, 0], [0, 1, 0], resolution=(1, 1)),
                         photons=n)
            elif what == "resolution":
                cam = g.Camera([0, 0, 3.9], [0, 0, 0], [0, 1, 0], resolution=(n, max(1, n // 3)))
                if cam.width * cam.height <= 16:
                    g.render(scene(), cam, photons=64)
                else:  # a large image is refused before its memory is taken
                    try:
                        g.render(scene(), cam, photons=64, indirect=False)
                    except ValueError:
                        pass
            elif what == "ink_rows":
                if n <= 64:  # small: rendered (n = 0 is refused)
                    _core.render_ink_landscape(n, 64, 0, 1, threads=1)
                else:  # over 4 GiB: refused before the allocation
                    _core.render_ink_landscape(min(max(n, 1400), (1 << 32) - 1), 1 << 20, 0, 1 << 20, threads=1)
            elif what == "vt_slots":
                _core.VirtualTexture(pack(), (n, max(1, n // 7)))
            elif what == "sample_empty":
                vt = g.VirtualTexture(pack(), slots=(8, 8))
                rgb, lv = vt.sample(0, np.zeros(n % 3), np.zeros(n % 3))
                assert rgb.shape == (n % 3, 3) and lv.shape == (n % 3,)
            return "ok"
        raise AssertionError(k)

    _pack = None
    def pack():
        global _pack
        if _pack is None:
            img = np.random.default_rng(1).integers(0, 256, (40, 60, 3), dtype=np.uint8)
            _pack = g.build_pack(img, sys.argv[1], tile_size=16, border=2)
        return _pack

    for line in sys.stdin:
        c = json.loads(line)
        try:
            out = {"outcome": run(c)}
        except Exception as e:
            out = {"outcome": "error", "type": type(e).__name__, "message": str(e),
                   "trace": traceback.format_exc()[-1500:]}
        sys.stdout.write(json.dumps(out) + "\n")
        sys.stdout.flush()
''')


class Worker:
    """A long-lived subprocess running cases; restarted after a crash."""

    def __init__(self, pack_dir):
        self.pack_dir = pack_dir
        self.proc = None
        self.counts = {}    # cases per family
        self.outcomes = {}  # family -> {"ok" or exception type: cases}
        self.examples = {}  # (family, message start) -> first case

    def start(self):
        env = dict(os.environ, PYTHONFAULTHANDLER="1")
        self.proc = subprocess.Popen([sys.executable, "-c", WORKER, str(self.pack_dir)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)

    def run(self, case):
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        self.counts[case["kind"]] = self.counts.get(case["kind"], 0) + 1
        import selectors
        self.proc.stdin.write(json.dumps(case) + "\n")
        self.proc.stdin.flush()
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        if not sel.select(CASE_TIMEOUT):
            self.proc.kill()
            self.proc.wait()
            self.proc = None
            pytest.fail(f"case hung for {CASE_TIMEOUT} s: {case}")
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            err = self.proc.stderr.read()[-3000:]
            self.proc = None
            pytest.fail(f"the worker died (exit code {code}) on case {case}:\n{err}")
        out = json.loads(line)
        per = self.outcomes.setdefault(case["kind"], {})
        tag = out["outcome"] if out["outcome"] == "ok" else out["type"]
        per[tag] = per.get(tag, 0) + 1
        if out["outcome"] == "error":
            self.examples.setdefault((case["kind"], out["message"][:60]), case)
        if out["outcome"] == "error":
            assert out["type"] in CLEAN, f"{out['type']} on {case}:\n{out['trace']}"
            assert out["message"].strip(), f"empty {out['type']} message on {case}"
            assert "Traceback" not in out["message"]
        return out

    def close(self):
        if self.proc is not None and self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()


@pytest.fixture(scope="module")
def worker(tmp_path_factory):
    w = Worker(tmp_path_factory.mktemp("fuzzcore") / "p")
    yield w
    w.close()
    print("\nfuzz cases per family (none crashed):", json.dumps(w.counts, sort_keys=True))
    print("outcomes:", json.dumps(w.outcomes, sort_keys=True))


def enc(x):
    """Floats to JSON: non-finite ones as strings the worker turns back into floats."""
    if isinstance(x, (list, tuple)):
        return [enc(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return x


# Coordinates: ordinary, tiny, huge, at the bounds, non-finite.
coord = st.one_of(
    st.floats(-10, 10),
    st.sampled_from([0.0, -0.0, 1e-300, 5e-324, 1e12, -1e12, 1.0000001e12, 1e17, 1e18, 2e18, 1e38, 3.5e38,
                     1e300, math.inf, -math.inf, math.nan]),
    st.floats(allow_nan=True, allow_infinity=True),
)
# Ordinary values often enough that valid cameras, rays and meshes really render and trace
# (far cameras included: 1e11 is inside the bound and must render, not abort).
ordinary = st.one_of(st.floats(-3, 3), st.sampled_from([0.0, 1.0, -1.0, 1e11, -9.9e11]))
vec = st.one_of(st.lists(ordinary, min_size=3, max_size=3), st.lists(coord, min_size=3, max_size=3))
positive = st.one_of(st.floats(0.01, 10), coord)
size = st.one_of(st.integers(0, 70), st.sampled_from([1 << 20, 1 << 24, (1 << 24) + 1, 1 << 31, (1 << 32) - 1,
                                                    1 << 32, 1 << 40, 1 << 61, (1 << 63) - 1, (1 << 64) - 1]),
                 st.integers(0, (1 << 64) - 1))

PROFILE = dict(deadline=None, derandomize=True, suppress_health_check=list(HealthCheck), database=None)


def scaled(n):
    return settings(max_examples=n, **PROFILE)


def camera_cases(n):
    @scaled(n)
    @given(position=vec, look_at=vec, up=vec, fov=st.one_of(st.floats(1, 179), coord),
           resolution=st.tuples(st.sampled_from([1, 2, 4, 8, 8, 8, 65536, 65537, 1 << 31]),
                                st.sampled_from([1, 3, 8, 8, 8, 70000])))
    def run(worker, position, look_at, up, fov, resolution):
        worker.run(dict(kind="camera", position=enc(position), look_at=enc(look_at), up=enc(up), fov=enc(fov),
                        resolution=list(resolution)))
    return run


def camera_raw_cases(n):
    # Half the cases have every value ordinary (they must render), half draw each value wild.
    @scaled(n)
    @given(sane=st.booleans(), data=st.data())
    def run(worker, sane, data):
        v3 = st.lists(ordinary, min_size=3, max_size=3) if sane else vec
        position, forward, up = data.draw(v3), data.draw(v3), data.draw(v3)
        tx, ty = data.draw(st.floats(0.05, 5) if sane else positive), data.draw(st.floats(0.05, 5) if sane else positive)
        w = data.draw(st.sampled_from([1, 4, 8]) if sane else st.sampled_from([0, 1, 8, 1 << 19, 1 << 20]))
        h = data.draw(st.sampled_from([1, 2, 8]) if sane else st.sampled_from([1, 8, -1]))
        worker.run(dict(kind="camera_raw", position=enc(position), forward=enc(forward), up=enc(up), tx=enc(tx),
                        ty=enc(ty), width=w, height=h))
    return run


def stereo_cases(n):
    @scaled(n)
    @given(position=st.one_of(st.just([0.0, 0.0, 3.9]), vec), ipd=st.one_of(st.floats(0, 1), coord))
    def run(worker, position, ipd):
        worker.run(dict(kind="stereo", position=enc(position), ipd=enc(ipd)))
    return run


def ray_cases(n):
    @scaled(n)
    @given(o=vec, d=vec)
    def run(worker, o, d):
        worker.run(dict(kind="ray", o=enc(o), d=enc(d)))
    return run


def mesh_cases(n):
    @scaled(n)
    @given(sane=st.booleans(), data=st.data())
    def run(worker, sane, data):
        if sane:  # a unit triangle moved by up to 0.3 per coordinate: never degenerate
            base = [0, 0, 0, 1, 0, 0, 0, 1, 0]
            vertices = [b + x for b, x in zip(base, data.draw(st.lists(st.floats(-0.3, 0.3), min_size=9, max_size=9)))]
        else:
            vertices = data.draw(st.lists(coord, min_size=9, max_size=9))
        o = data.draw(st.lists(st.floats(-3, 3), min_size=3, max_size=3) if sane else vec)
        d = data.draw(st.lists(st.floats(-1, 1), min_size=3, max_size=3) if sane else vec)
        worker.run(dict(kind="mesh", vertices=enc(vertices), o=enc(o), d=enc(d)))
    return run


SIZE_TARGETS = ["loader_threads", "loader_queue", "loader_pool", "trace_count", "trace_threads", "render_threads",
                "render_spp", "render_photons", "resolution", "vt_slots", "sample_empty", "ink_rows"]


def size_cases(n):
    @scaled(n)
    @given(what=st.sampled_from(SIZE_TARGETS), n=size)
    def run(worker, what, n):
        worker.run(dict(kind="sizes", what=what, n=n))
    return run


FAMILIES = {"camera": (camera_cases, 60), "camera_raw": (camera_raw_cases, 40), "stereo": (stereo_cases, 30),
            "ray": (ray_cases, 150), "mesh": (mesh_cases, 30), "sizes": (size_cases, 80)}


@pytest.mark.parametrize("family", list(FAMILIES))
def test_fuzz_core(worker, family):
    make, n = FAMILIES[family]
    before = worker.counts.get(family, 0)
    make(n)(worker)
    assert worker.counts.get(family, 0) - before >= min(n, 10)  # the cases did run


@pytest.mark.fuzz
@pytest.mark.parametrize("family", list(FAMILIES))
def test_fuzz_core_long(worker, family, request):
    if "fuzz" not in (request.config.getoption("markexpr") or ""):
        pytest.skip("long fuzz run: select it with -m fuzz")
    make, n = FAMILIES[family]
    make(10 * n)(worker)

"""Fuzzing load_room: random transforms (NaN, inf, huge), random and corrupted bytes, random
JSON edits and random placeholder corners. The outcome is a RoomSpec whose slots are sound, or
a clean ValueError / OSError; never another exception."""

import json
import math
import os
import shutil
import struct
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings, strategies as st

from gigascroll.room.example import EXAMPLE_PAINTINGS, write_example_room
from gigascroll.room.spec import RoomSpec
from gigascroll.room.files import load_room, write_gltf
from gigascroll.room.sizes import painting_sizes

# GIGASCROLL_FUZZ_EXAMPLES raises the number of cases for a longer run (default 40 each).
SETTINGS = settings(max_examples=int(os.environ.get("GIGASCROLL_FUZZ_EXAMPLES", 40)),
                    deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])
PAINTINGS = {**EXAMPLE_PAINTINGS, "p": 2.0}  # indices 0, 1 as in the example
_DIR = Path(tempfile.mkdtemp(prefix="fuzz-rooms-"))
_EXAMPLE = {s: write_example_room(_DIR / f"example{s}").read_bytes()
            for s in (".glb", ".gltf", ".obj", ".ply")}
_MTL = (_DIR / "example.mtl").read_bytes()


def teardown_module():
    shutil.rmtree(_DIR, ignore_errors=True)

floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                   st.sampled_from([0.0, 1.0, -1.0, 1e-30, 1e30, 1e300]),
                   st.floats(-10, 10), st.floats(-10, 10))  # mostly sane, so rooms load too


def outcome(path, paintings=PAINTINGS):
    try:
        spec = load_room(path, paintings)
    except (ValueError, OSError) as e:
        assert str(e)
        return None
    assert isinstance(spec, RoomSpec)
    for s in spec.surfaces:
        assert np.isfinite(s.vertices).all() and np.abs(s.vertices).max() <= 1e4
        assert all(0 <= a < 1 for a in s.albedo)
        assert s.triangles.min() >= 0 and s.triangles.max() < len(s.vertices)
    assert any(max(s.emission) > 0 for s in spec.surfaces)
    for slot in spec.paintings:
        u, v = np.array(slot.u_axis), np.array(slot.v_axis)
        assert abs(np.linalg.norm(u) - 1) < 1e-9 and abs(np.linalg.norm(v) - 1) < 1e-9
        assert abs(np.dot(u, v)) < 1e-6
        sizes = painting_sizes(paintings)
        (size,) = [p for i, p in enumerate(sizes) if slot.painting in (i, p.name)][:1]
        assert abs(slot.width_m / slot.height_m / size.aspect - 1) <= 0.01 + 1e-9
    return spec


@SETTINGS
@given(suffix=st.sampled_from([".glb", ".gltf", ".obj", ".ply"]), data=st.binary(max_size=400))
def test_random_bytes(suffix, data):
    path = _DIR / f"random{suffix}"
    path.write_bytes(data)
    outcome(path)


@SETTINGS
@given(suffix=st.sampled_from([".glb", ".gltf", ".obj", ".ply"]),
       edits=st.lists(st.tuples(st.floats(0, 1), st.integers(0, 255)), min_size=1, max_size=8),
       cut=st.one_of(st.none(), st.floats(0, 1)))
def test_corrupted_example(suffix, edits, cut):
    data = bytearray(_EXAMPLE[suffix])
    for where, value in edits:
        data[min(int(where * len(data)), len(data) - 1)] = value
    if cut is not None:
        data = data[:int(cut * len(data))]
    path = _DIR / f"corrupt{suffix}"
    path.write_bytes(bytes(data))
    (_DIR / "corrupt.mtl").write_bytes(_MTL.replace(b"example", b"corrupt"))
    if suffix == ".obj":
        path.write_bytes(bytes(data).replace(b"example.mtl", b"corrupt.mtl"))
    outcome(path)


json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-2**40, 2**40), floats, st.text(max_size=8)),
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=6)


def paths_of(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from paths_of(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from paths_of(v, prefix + (i,))


@SETTINGS
@given(choice=st.floats(0, 1), value=json_values, delete=st.booleans())
def test_json_edits(choice, value, delete):
    header = json.loads(_EXAMPLE[".gltf"])
    paths = [p for p in paths_of(header) if p and p[0] != "buffers"]
    target = paths[min(int(choice * len(paths)), len(paths) - 1)]
    parent = header
    for key in target[:-1]:
        parent = parent[key]
    if delete and isinstance(parent, dict):
        del parent[target[-1]]
    else:
        parent[target[-1]] = value
    path = _DIR / "edited.gltf"
    path.write_text(json.dumps(header))
    outcome(path)


@SETTINGS
@given(translation=st.lists(floats, min_size=3, max_size=3),
       rotation=st.lists(floats, min_size=4, max_size=4),
       scale=st.lists(floats, min_size=3, max_size=3),
       matrix=st.one_of(st.none(), st.lists(floats, min_size=16, max_size=16)),
       uniform=st.booleans())
def test_random_transforms(translation, rotation, scale, matrix, uniform):
    if uniform:  # keeps the placeholder's aspect, so the accepted path is reached too
        scale = [scale[0]] * 3
    nodes = [dict(name="lamp", vertices=[[0, 3, 0], [1, 3, 0], [0, 3, 1]],
                  triangles=[[0, 2, 1]], albedo=(0.5, 0.5, 0.5), emission=(1, 1, 1)),
             dict(name="group", children=[2]),
             dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]],
                  triangles=[[0, 1, 2], [0, 2, 3]])]
    if matrix is None:
        nodes[1].update(translation=translation, rotation=rotation, scale=scale)
    else:
        nodes[1]["matrix"] = np.array(matrix).reshape(4, 4)
    path = write_gltf(nodes, _DIR / "transformed.glb")
    spec = outcome(path)
    if spec is not None and matrix is None and all(math.isfinite(x) for x in
                                                   translation + rotation + scale):
        assert len(spec.paintings) == 1


@SETTINGS
@given(corners=st.lists(st.lists(st.one_of(st.floats(-3, 3), st.sampled_from([0.0, 1.0, 2.0])),
                                 min_size=3, max_size=3), min_size=4, max_size=4),
       triangles=st.sampled_from([[[0, 1, 2], [0, 2, 3]], [[0, 1, 2], [2, 3, 0]],
                                  [[0, 1, 2], [0, 3, 2]], [[0, 1, 2], [1, 2, 3]],
                                  [[0, 1, 2]], [[0, 1, 2], [0, 2, 3], [0, 1, 3]]]),
       rectangle=st.booleans(),
       aspect=st.one_of(st.sampled_from([2.0, 0.5, 2.015]), st.floats(0.5, 4.0)))
def test_random_placeholder_corners(corners, triangles, rectangle, aspect):
    if rectangle:  # a true rectangle with random axes, so the accepted path is fuzzed too
        rng = np.random.default_rng(abs(hash(str(corners))) % 2**32)
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        o = np.array(corners[0])
        a, b = q[:, 0] * aspect, q[:, 1]
        corners = [o, o + a, o + a + b, o + b]
    nodes = [dict(name="lamp", vertices=[[0, 9, 0], [1, 9, 0], [0, 9, 1]],
                  triangles=[[0, 2, 1]], albedo=(0.5, 0.5, 0.5), emission=(1, 1, 1)),
             dict(name="painting:p", vertices=np.array(corners, dtype=np.float64),
                  triangles=triangles)]
    path = write_gltf(nodes, _DIR / "corners.glb")
    spec = outcome(path, {"p": 2.0})
    if spec is not None:
        (slot,) = spec.paintings
        assert abs(slot.width_m / slot.height_m / 2.0 - 1) <= 0.01 + 1e-9


@SETTINGS
@given(count=st.integers(0, 2**62), component=st.sampled_from([5126, 5125, 5121, 1, None]),
       offset=st.integers(-5, 2**40))
def test_hostile_accessor_counts(count, component, offset):
    header = json.loads(_EXAMPLE[".gltf"])
    a = header["accessors"][0]
    a["count"], a["componentType"], a["byteOffset"] = count, component, offset
    if count % 3 == 0:
        del a["bufferView"]  # a zero-filled accessor of `count` elements
    path = _DIR / "hostile.gltf"
    path.write_text(json.dumps(header))
    outcome(path)


def test_glb_header_lies():
    data = bytearray(_EXAMPLE[".glb"])
    for field, value in ((8, 2**31), (12, 2**31), (4, 1)):
        bad = bytearray(data)
        struct.pack_into("<I", bad, field, value)
        path = _DIR / "lies.glb"
        path.write_bytes(bytes(bad))
        assert outcome(path) is None


@SETTINGS
@given(children=st.lists(st.lists(st.one_of(st.integers(-1, 7), st.just("x"), st.just(True)),
                                  max_size=4), min_size=6, max_size=6),
       roots=st.lists(st.integers(-1, 7), max_size=4))
def test_random_node_graphs(children, roots):
    """Any children / roots structure (cycles, shared children, bad indices)."""
    header = json.loads(_EXAMPLE[".gltf"])
    for node, kids in zip(header["nodes"], children):
        node["children"] = kids
    header["scenes"][0]["nodes"] = roots
    path = _DIR / "graph.gltf"
    path.write_text(json.dumps(header))
    outcome(path)

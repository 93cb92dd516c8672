"""Hostile room files, second round (issue 43, families 3, 4 and 6), each case that could hang
or exhaust memory run in a forked child with a timeout and an address-space cap
(fuzz_support.Worker):

  - no hang: a glTF image or buffer, an OBJ's mtllib, an MTL's map_Kd, or the room file
    itself that is a FIFO, a link to /dev/zero or a directory is refused at once (exit 2, one
    line), and so is a FIFO swapped in between the check and the open;
  - memory bounded by the file: a 1.9 MB .glb whose one 50k-triangle mesh is drawn by 19000
    nodes is refused from its structure before an instance is expanded (it reached 3.8 GiB);
    an unused 4 GiB (sparse) image or buffer is never read; the triangle budget counted from
    the structure equals the triangles the loader expands (brute force, random node trees);
  - the glTF 2.0 specification: numbers given as strings, a projective matrix, a missing
    mesh, byteStride 1, float indices, unknown extensionsRequired ... are ValueErrors, while
    the equivalent valid forms load the same room."""

from __future__ import annotations

import base64
import copy
import json
import os
from pathlib import Path

import numpy as np
import pytest
from fuzz_support import CASES, cli_message_ok, count_case, fork_worker, fuzz_settings  # noqa: F401
from hypothesis import given
from hypothesis import strategies as st

from gallery_checks import uniform_pack
from gigascroll import _core
from gigascroll.room import assets as room_assets, gltf as room_gltf
from gigascroll.room.example import EXAMPLE_PAINTINGS, write_example_room
from gigascroll.room.files import load_room, write_gltf
from gigascroll.room.gltf_nodes import glb_bytes as _glb_bytes

MEMORY = 3 << 30  # the child's address space (the forked worker already maps ~1 GiB)


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    return uniform_pack(tmp_path_factory.mktemp("pack") / "p.pack",
                        {"landscape": (90, 120, 60), "hanging_scroll": (200, 40, 40)},
                        size=(96, 64))


def example_gltf(tmp_path: Path, external: bool = True) -> tuple[Path, dict]:
    """The example room as .gltf, its buffer in room.bin beside it (or embedded)."""
    path = write_example_room(tmp_path / "room.gltf")
    header = json.loads(path.read_text())
    if external:
        blob = base64.b64decode(header["buffers"][0]["uri"].split(",", 1)[1])
        (tmp_path / "room.bin").write_bytes(blob)
        header["buffers"][0]["uri"] = "room.bin"
        path.write_text(json.dumps(header))
    return path, header


def make_hostile(target: Path, kind: str):
    """A FIFO, a symbolic link to /dev/zero or a directory at `target`."""
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "dev-zero":
        os.symlink("/dev/zero", target)
    else:
        target.mkdir()


def room_naming(tmp_path: Path, where: str, kind: str) -> Path:
    """A room that names a hostile file at `where`."""
    if where in ("gltf-image", "gltf-buffer"):
        path, header = example_gltf(tmp_path)
        if where == "gltf-image":
            header["images"] = [{"uri": "texture.png"}]
            make_hostile(tmp_path / "texture.png", kind)
        else:
            header["buffers"][0]["uri"] = "data.bin"
            make_hostile(tmp_path / "data.bin", kind)
        path.write_text(json.dumps(header))
        return path
    if where == "room-file":
        path = tmp_path / "room.glb"
        make_hostile(path, kind)
        return path
    path = write_example_room(tmp_path / "room.obj")
    if where == "obj-mtllib":
        path.write_text(path.read_text().replace("mtllib room.mtl", "mtllib other.mtl"))
        make_hostile(tmp_path / "other.mtl", kind)
    else:  # mtl-map_Kd
        mtl = tmp_path / "room.mtl"
        mtl.write_text(mtl.read_text().replace("Kd ", "map_Kd -s 1 1 1 texture.png\nKd ", 1))
        make_hostile(tmp_path / "texture.png", kind)
    return path


# ---- family 3: no hang -------------------------------------------------------------------------


@pytest.mark.parametrize("where", ["gltf-image", "gltf-buffer", "obj-mtllib", "mtl-map_Kd",
                                   "room-file"])
@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "directory"])
def test_named_file_that_is_not_regular_is_refused(fork_worker, pack, tmp_path, where, kind):
    room = room_naming(tmp_path, where, kind)
    argv = ["render", "--room", str(room), "--pack", str(pack.path), "-o",
            str(tmp_path / "out.png"), "--width", "8", "--height", "8", "--lighting", "unlit"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": MEMORY}, timeout=60)
    assert cli_message_ok(o) is None and o.code == 2, o.describe()
    assert "not a regular file" in o.stderr, o.describe()
    assert not (tmp_path / "out.png").exists()


@pytest.mark.parametrize("where", ["gltf-image", "mtl-map_Kd"])
def test_regular_unused_files_are_fine(tmp_path, where):
    """The same rooms with a regular (or no) file there load: the texture is not used."""
    room = room_naming(tmp_path, where, "directory")
    (tmp_path / "texture.png").rmdir()
    spec = load_room(room, EXAMPLE_PAINTINGS)  # missing: fine, it is never read
    (tmp_path / "texture.png").write_bytes(b"not even a png")
    again = load_room(room, EXAMPLE_PAINTINGS)
    assert len(again.surfaces) == len(spec.surfaces) > 0


def test_fifo_swapped_in_after_the_check_does_not_block(fork_worker, tmp_path):
    """The race: the stat saw a regular file, a FIFO is there at the open. O_NONBLOCK keeps
    the open from waiting for a writer and fstat refuses it."""
    fifo = tmp_path / "swap.bin"
    os.mkfifo(fifo)
    code = (
        "from gigascroll.room import assets as room_assets\n"
        "room_assets.check_regular = lambda *a, **k: None  # the check passed, then a swap\n"
        "try:\n"
        f"    room_assets.read_regular({str(fifo)!r}, 'buffer', 1 << 20)\n"
        "except OSError as e:\n"
        "    assert 'not a regular file (a FIFO)' in str(e), e\n"
        "else:\n"
        "    raise SystemExit('read a FIFO')\n")
    o = fork_worker.run({"kind": "python", "code": code}, timeout=30)
    assert o.code == 0 and not o.timeout, o.describe()


# ---- family 4: memory bounded by the file's structure -----------------------------------------


def instanced_glb(path: Path, triangles: int, instances: int) -> Path:
    """One grid mesh of `triangles` triangles drawn by `instances` nodes, one emitting
    material: a small file that expands to triangles x instances."""
    n = int(np.ceil(np.sqrt(triangles / 2))) + 1
    xs, zs = np.meshgrid(np.arange(n, dtype=np.float32) * 0.01,
                         np.arange(n, dtype=np.float32) * 0.01)
    v = np.stack([xs.ravel(), np.zeros(n * n, np.float32), zs.ravel()], 1)
    q = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    t = np.concatenate([np.stack([q, q + n, q + 1], 1),
                        np.stack([q + 1, q + n, q + n + 1], 1)])[:triangles].astype(np.uint32)
    blob = v.tobytes() + t.tobytes()
    header = {"asset": {"version": "2.0"}, "scene": 0, "buffers": [{"byteLength": len(blob)}],
              "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": v.nbytes},
                              {"buffer": 0, "byteOffset": v.nbytes, "byteLength": t.nbytes}],
              "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(v),
                             "type": "VEC3", "min": v.min(0).tolist(), "max": v.max(0).tolist()},
                            {"bufferView": 1, "componentType": 5125, "count": t.size,
                             "type": "SCALAR"}],
              "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]},
                             "emissiveFactor": [1, 1, 1]}],
              "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                          "material": 0}]}],
              "nodes": [{"mesh": 0, "translation": [0, 0.001 * i, 0]} for i in range(instances)],
              "scenes": [{"nodes": list(range(instances))}]}
    path.write_bytes(_glb_bytes(json.dumps(header).encode(), blob))
    return path


def test_instanced_room_is_refused_from_its_structure(fork_worker, pack, tmp_path):
    """1.9 MB: 50k triangles x 19000 nodes (950M triangles, ~34 GB expanded): refused
    before any instance is expanded, in a child whose address space is capped."""
    room = instanced_glb(tmp_path / "instanced.glb", 50_000, 19_000)
    assert room.stat().st_size < 2_500_000
    argv = ["render", "--room", str(room), "--pack", str(pack.path), "-o",
            str(tmp_path / "out.png"), "--width", "8", "--height", "8", "--lighting", "unlit"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": MEMORY}, timeout=120)
    assert cli_message_ok(o) is None and o.code == 2, o.describe()
    assert "950000000 triangles drawn (19000 mesh instances)" in o.stderr, o.stderr
    assert f"more than the {room_assets.MAX_TRIANGLES} a room can have" in o.stderr


def test_triangle_cap_is_what_the_bake_can_hold():
    """A triangle has at least 3 lattice points (n = 1: its corners); the core's bake holds
    BAKE_MAX_POINTS (the C++ test GalleryLimits checks the bake refuses one more)."""
    assert room_assets.MAX_TRIANGLES == _core.BAKE_MAX_POINTS // 3 == 11_184_810


def sparse(path: Path, size: int = 4 << 30) -> Path:
    with open(path, "wb") as f:
        f.truncate(size)
    return path


@pytest.mark.parametrize("what", ["image", "unused-buffer", "used-buffer-prefix"])
def test_unused_bytes_are_not_read(fork_worker, tmp_path, what):
    """A 4 GiB sparse file the room names is not read (the child has 3 GiB of address space in
    all): an image, a buffer no accessor reads, or the bytes past a buffer's byteLength."""
    path, header = example_gltf(tmp_path)
    if what == "image":
        header["images"] = [{"uri": "big.png"}]
        sparse(tmp_path / "big.png")
    elif what == "unused-buffer":
        header["buffers"].append({"byteLength": 4 << 30, "uri": "big.bin"})
        sparse(tmp_path / "big.bin")
    else:
        blob = (tmp_path / "room.bin").read_bytes()
        sparse(tmp_path / "room.bin")
        with open(tmp_path / "room.bin", "r+b") as f:
            f.write(blob)
    path.write_text(json.dumps(header))
    code = (f"from gigascroll.room.files import load_room\n"
            f"spec = load_room({str(path)!r}, {EXAMPLE_PAINTINGS!r})\n"
            f"assert len(spec.paintings) == 2 and len(spec.surfaces) == 3, spec\n")
    o = fork_worker.run({"kind": "python", "code": code, "memory": MEMORY}, timeout=60)
    assert o.code == 0 and not o.timeout, o.describe()


def test_obj_and_ply_budgets_before_trimesh(tmp_path, monkeypatch):
    """OBJ faces and PLY elements are counted from the text before trimesh expands them."""
    import trimesh

    obj = write_example_room(tmp_path / "room.obj")
    faces = sum(len(line.split()) - 3 for line in obj.read_text().splitlines()
                if line.startswith("f "))
    monkeypatch.setattr(room_assets, "MAX_TRIANGLES", faces - 1)
    monkeypatch.setattr(trimesh, "load", lambda *a, **k: pytest.fail("trimesh was called"))
    with pytest.raises(ValueError, match=f"room.obj: {faces} triangles, more than the "
                                         f"{faces - 1} a room can have"):
        load_room(obj, EXAMPLE_PAINTINGS)
    monkeypatch.undo()
    ply = tmp_path / "huge.ply"
    ply.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                    b"property float y\nproperty float z\nelement face 1000000000000\n"
                    b"property list uchar int vertex_indices\nend_header\n" + bytes(36))
    with pytest.raises(ValueError, match="huge.ply: 1000000000000 triangles"):
        load_room(ply, EXAMPLE_PAINTINGS)


tree_shapes = st.lists(st.tuples(st.integers(-1, 8), st.integers(0, 3)), min_size=1,
                       max_size=10)
_MESHES = [dict(vertices=[[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], triangles=[[0, 1, 2], [0, 2, 3]]),
           dict(vertices=[[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1], [0, 2, 0], [1, 2, 0]],
                triangles=[[0, 1, 2], [0, 2, 3], [0, 1, 5], [0, 5, 4]]),
           dict(vertices=[[0, 3, 0], [1, 3, 0], [0, 3, 1], [1, 3, 1], [0, 3, 2], [1, 3, 2]],
                triangles=[[0, 1, 2], [3, 4, 5]])]  # read as a strip of 6 indices below


@fuzz_settings(40)
@given(shape=tree_shapes, roots_only=st.booleans())
def test_budget_counts_what_the_loader_expands(tmp_path_factory, shape, roots_only):
    """Random node forests drawing 3 meshes (2 and 4 triangles, and a strip of 6 indices: 4
    triangles), some nodes outside the scene: the triangles counted from the structure equal
    those trimesh and the loader expand (brute force)."""
    count_case("rooms-budget")
    nodes = []
    for i, (_, mesh) in enumerate(shape):
        node = dict(name=f"n{i}", translation=[0.1 * i, 0, 0])
        if mesh < 3:
            node.update(_MESHES[mesh], albedo=(0.5, 0.5, 0.5), emission=(1, 1, 1))
        nodes.append(node)
    children = set()
    for i, (parent, _) in enumerate(shape):
        if 0 <= parent < i:  # trees: a parent before its child
            nodes[parent].setdefault("children", []).append(i)
            children.add(i)
    roots = [i for i in range(len(nodes)) if i not in children]
    path = write_gltf(nodes, tmp_path_factory.mktemp("budget") / "room.gltf",
                      roots=roots[:1] if roots_only else roots)
    header = json.loads(path.read_text())
    for n, (_, mesh) in zip(header["nodes"], shape):
        if mesh == 2:
            header["meshes"][n["mesh"]]["primitives"][0]["mode"] = 5  # TRIANGLE_STRIP
    path.write_text(json.dumps(header))
    drawn = room_gltf.check_gltf(header, path)
    counted = sum(room_gltf._mesh_size(header, header["meshes"][header["nodes"][i]["mesh"]])[0]
                  for i in drawn if "mesh" in header["nodes"][i])
    expected = 0  # by hand: the nodes under the scene's roots
    stack = list(header["scenes"][0]["nodes"])
    while stack:
        i = stack.pop()
        expected += [2, 4, 4, 0][shape[i][1]]
        stack += header["nodes"][i].get("children", [])
    assert counted == expected
    try:
        spec = load_room(path, {"p": 2.0})
    except ValueError as e:
        assert "no light" in str(e) and counted == 0
        return
    assert sum(len(s.triangles) for s in spec.surfaces) == counted


# ---- family 6: the glTF 2.0 specification ------------------------------------------------------


def _camera(h):
    return next(n for n in h["nodes"] if "camera" in n)


def _mesh_node(h):
    return next(n for n in h["nodes"] if "mesh" in n)


def _stride(h, value):
    h["bufferViews"][h["accessors"][0]["bufferView"]]["byteStride"] = value


SPEC_VIOLATIONS = [
    ("accessor count as a string", lambda h: h["accessors"][0].update(count=str(h["accessors"][0]["count"])),
     r"accessors\[0\]\.count: '\d+' is not of type 'integer'"),
    ("translation as strings", lambda h: h["nodes"][0].update(translation=["2", "0", "-1"]),
     r"node 'gallery': nodes\[0\]\.translation\[0\]: '2' is not of type 'number'"),
    ("albedo as strings", lambda h: h["materials"][0]["pbrMetallicRoughness"].update(
        baseColorFactor=["0.5", "0.5", "0.5", "1"]), r"albedo .*'0.5' is not of type 'number'"),
    ("emissive strength as a string", lambda h: next(
        m for m in h["materials"] if "extensions" in m)["extensions"][
        "KHR_materials_emissive_strength"].update(emissiveStrength="6"), r"emissiveStrength"),
    ("camera target as strings", lambda h: _camera(h).setdefault("extras", {}).update(
        target=["0", "1", "0"]), r"extras.target must be 3 numbers"),
    ("projective matrix", lambda h: h["nodes"][0].update(
        matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5, 0, 0, 0, 1], translation=None,
        rotation=None),
     r"node 'gallery': matrix bottom row \[0, 0, 0\.5, 1\] is not \[0, 0, 0, 1\]"),
    ("matrix beside TRS", lambda h: h["nodes"][0].update(
        matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]),
     r"node 'gallery': nodes\[0\]: a matrix beside translation, rotation or scale"),
    ("missing mesh", lambda h: _mesh_node(h).update(mesh=len(h["meshes"])),
     r"node 'walls': its mesh 5 is not among the file's 5 meshes"),
    ("missing camera", lambda h: _camera(h).update(camera=3), r"node 'camera': its camera 3"),
    ("byteStride 1", lambda h: _stride(h, 1), r"byteStride: 1 is less than the minimum of 4"),
    ("byteStride below the element", lambda h: _stride(h, 8),
     r"byteStride 8 is smaller than accessors\[0\]'s element \(12 bytes\)"),
    ("float indices", lambda h: h["accessors"][1].update(componentType=5126),
     r"indices must be an unsigned byte, short or int SCALAR, are SCALAR of component type 5126"),
    ("signed indices", lambda h: h["accessors"][1].update(componentType=5122), r"indices must"),
    ("integer positions", lambda h: h["accessors"][0].update(componentType=5125),
     r"POSITION must be float VEC3"),
    ("unknown required extension", lambda h: h.update(
        extensionsRequired=["KHR_draco_mesh_compression"],
        extensionsUsed=["KHR_draco_mesh_compression"]),
     r"requires glTF extensions this reader does not implement: 'KHR_draco_mesh_compression'"),
    ("missing scene", lambda h: h.update(scene=4), r"scene 4 is not among the file's 1 scenes"),
    ("a child as a root", lambda h: h["scenes"][0]["nodes"].append(1),
     r"scene 0 lists node 1 as a root, but it is the child of node 0"),
    ("missing material", lambda h: h["meshes"][0]["primitives"][0].update(material=99),
     r"names material 99, which does not exist"),
    ("missing accessor", lambda h: h["meshes"][0]["primitives"][0]["attributes"].update(
        NORMAL=99), r"names an accessor that does not exist"),
    ("strided indices", lambda h: h["bufferViews"][h["accessors"][1]["bufferView"]].update(
        byteStride=4), r"the indices' buffer view has a byteStride"),
]


def _apply(change, header):
    h = copy.deepcopy(header)
    change(h)
    for n in h["nodes"]:  # a change may drop a key by setting it to None
        for k in [k for k, v in n.items() if v is None]:
            del n[k]
    return h


@pytest.mark.parametrize("name,change,message", SPEC_VIOLATIONS, ids=[v[0] for v in SPEC_VIOLATIONS])
def test_spec_violations_are_errors(tmp_path, name, change, message):
    path, header = example_gltf(tmp_path, external=False)
    assert len(load_room(path, EXAMPLE_PAINTINGS).surfaces) == 3  # the unchanged file loads
    path.write_text(json.dumps(_apply(change, header)))
    with pytest.raises(ValueError, match=r"room.gltf: .*" + message):
        load_room(path, EXAMPLE_PAINTINGS)


def _matrix_of_trs(n):
    from gigascroll.room.gltf_nodes import _local_matrix

    return [float(x) for x in _local_matrix(n).T.ravel()]


SPEC_EQUIVALENTS = [
    ("explicit byteStride 12", lambda h: _stride(h, 12)),
    ("byteStride 16 with padding", None),
    ("the supported extension required", lambda h: h.update(
        extensionsRequired=["KHR_materials_emissive_strength"])),
    ("matrix instead of TRS", lambda h: [n.update(matrix=_matrix_of_trs(n), translation=None,
                                                  rotation=None, scale=None)
                                         for n in h["nodes"] if "translation" in n]),
    ("unsigned short indices", None),
]


def _padded_positions(header):
    """POSITION of the first accessor re-laid with byteStride 16 (4 bytes of padding)."""
    a = header["accessors"][0]
    uri = header["buffers"][0]["uri"]
    blob = bytearray(base64.b64decode(uri.split(",", 1)[1]))
    view = header["bufferViews"][a["bufferView"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    v = np.frombuffer(bytes(blob[start:start + 12 * a["count"]]), np.float32).reshape(-1, 3)
    padded = np.zeros((len(v), 4), np.float32)
    padded[:, :3] = v
    padded[:, 3] = np.nan  # the padding is never read
    header["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength":
                                  padded.nbytes, "byteStride": 16})
    blob += padded.tobytes()
    a["bufferView"], a["byteOffset"] = len(header["bufferViews"]) - 1, 0
    header["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;"
                            "base64," + base64.b64encode(bytes(blob)).decode()}


def _short_indices(header):
    """The first index accessor as unsigned shorts."""
    a = header["accessors"][1]
    blob = bytearray(base64.b64decode(header["buffers"][0]["uri"].split(",", 1)[1]))
    view = header["bufferViews"][a["bufferView"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    idx = np.frombuffer(bytes(blob[start:start + 4 * a["count"]]), np.uint32).astype(np.uint16)
    header["bufferViews"].append({"buffer": 0, "byteOffset": len(blob),
                                  "byteLength": idx.nbytes})
    blob += idx.tobytes() + b"\0" * (-idx.nbytes % 4)
    a.update(bufferView=len(header["bufferViews"]) - 1, byteOffset=0, componentType=5123)
    header["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;"
                            "base64," + base64.b64encode(bytes(blob)).decode()}


@pytest.mark.parametrize("name,change", SPEC_EQUIVALENTS, ids=[v[0] for v in SPEC_EQUIVALENTS])
def test_valid_forms_load_the_same_room(tmp_path, name, change):
    path, header = example_gltf(tmp_path, external=False)
    reference = load_room(path, EXAMPLE_PAINTINGS)
    if change is None:
        change = _padded_positions if "padding" in name else _short_indices
    path.write_text(json.dumps(_apply(change, header)))
    spec = load_room(path, EXAMPLE_PAINTINGS)
    for a, b in zip(spec.surfaces, reference.surfaces):
        np.testing.assert_allclose(a.vertices, b.vertices, atol=1e-9)
        np.testing.assert_array_equal(a.triangles, b.triangles)
    assert len(spec.surfaces) == len(reference.surfaces) == 3
    np.testing.assert_allclose([s.origin for s in spec.paintings],
                               [s.origin for s in reference.paintings], atol=1e-9)


@pytest.mark.parametrize("name,change,message", SPEC_VIOLATIONS[::4],
                         ids=[v[0] for v in SPEC_VIOLATIONS[::4]])
def test_spec_violations_on_the_command_line(fork_worker, pack, tmp_path, name, change, message):
    path, header = example_gltf(tmp_path, external=False)
    path.write_text(json.dumps(_apply(change, header)))
    argv = ["render", "--room", str(path), "--pack", str(pack.path), "-o",
            str(tmp_path / "out.png"), "--width", "8", "--height", "8", "--lighting", "unlit"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": MEMORY}, timeout=60)
    assert cli_message_ok(o) is None and o.code == 2, o.describe()


# ---- the fuzz families ------------------------------------------------------------------------


@fuzz_settings(20)
@given(where=st.sampled_from(["gltf-image", "gltf-buffer", "obj-mtllib", "mtl-map_Kd",
                              "room-file"]),
       kind=st.sampled_from(["fifo", "dev-zero", "directory"]))
def test_fuzz_rooms_naming_special_files(fork_worker, pack, tmp_path_factory, where, kind):
    count_case("rooms-special-files")
    tmp = tmp_path_factory.mktemp("special")
    room = room_naming(tmp, where, kind)
    argv = ["render", "--room", str(room), "--pack", str(pack.path), "-o", str(tmp / "o.png"),
            "--width", "8", "--height", "8", "--lighting", "unlit"]
    o = fork_worker.run({"kind": "cli", "argv": argv, "memory": MEMORY}, timeout=60)
    assert cli_message_ok(o) is None and o.code == 2, o.describe()


spec_values = st.one_of(st.integers(-3, 300), st.sampled_from([5120, 5121, 5122, 5123, 5125, 5126]),
                        st.floats(allow_nan=True), st.text(max_size=3),
                        st.just("1"), st.just([0, 0, 0, 1]), st.none())


@fuzz_settings(30)
@given(target=st.sampled_from(["stride", "index-type", "position-type", "mesh", "bottom-row",
                               "required", "scene", "count"]),
       value=spec_values, instances=st.integers(1, 40))
def test_fuzz_spec_rules(fork_worker, tmp_path_factory, target, value, instances):
    """Random values where the specification restricts them, and random instancing, in a
    child: a RoomSpec or ValueError / OSError, never another exception, a hang or a blow-up."""
    count_case("rooms-spec")
    tmp = tmp_path_factory.mktemp("spec")
    path, header = example_gltf(tmp, external=False)
    h = copy.deepcopy(header)
    if target == "stride":
        _stride(h, value)
    elif target == "index-type":
        h["accessors"][1]["componentType"] = value
    elif target == "position-type":
        h["accessors"][0]["componentType"] = value
    elif target == "mesh":
        _mesh_node(h)["mesh"] = value
    elif target == "bottom-row":
        h["nodes"][0].pop("translation", None), h["nodes"][0].pop("rotation", None)
        h["nodes"][0]["matrix"] = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, value, 1]
    elif target == "required":
        h["extensionsRequired"] = [value]
    elif target == "scene":
        h["scene"] = value
    else:
        h["accessors"][0]["count"] = value
    mesh = _mesh_node(h).get("mesh")
    h["nodes"] += [{"mesh": mesh, "translation": [0, 0.01 * i, 0]} for i in range(instances)]
    h["scenes"][0]["nodes"] += list(range(len(header["nodes"]), len(h["nodes"])))
    path.write_text(json.dumps(h))
    code = (f"from gigascroll.room.files import load_room\n"
            f"try:\n    load_room({str(path)!r}, {EXAMPLE_PAINTINGS!r})\n"
            f"except (ValueError, OSError) as e:\n    assert str(e)\n")
    o = fork_worker.run({"kind": "python", "code": code, "memory": MEMORY}, timeout=60)
    assert o.code == 0 and not o.timeout, o.describe()

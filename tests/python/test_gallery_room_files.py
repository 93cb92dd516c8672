"""Room files against an independent reference: the glTF JSON and buffers parsed here with
numpy (node transforms as numpy matrix products), the project's camera for the image
orientation, and the OBJ / PLY / glTF variants of one room against each other."""

import base64
import json
import math
import struct

import numpy as np
import pytest

from gigascroll import Camera
from gigascroll.room.example import EXAMPLE_PAINTINGS, main, write_example_room
from gigascroll.room.files import load_room, save_room, write_gltf
from gigascroll.room.builtin import ROOM_NAMES, builtin_room
from gigascroll.views.exhibition import SCROLL, TABLE4_PAINTINGS

# ---- an independent glTF reader (numpy only) -------------------------------------------------


def read_gltf(path):
    data = path.read_bytes()
    if path.suffix == ".glb":
        magic, version, _ = struct.unpack_from("<III", data)
        assert magic == 0x46546C67 and version == 2
        n_json, _ = struct.unpack_from("<II", data, 12)
        header = json.loads(data[20:20 + n_json])
        n_bin, _ = struct.unpack_from("<II", data, 20 + n_json)
        blob = data[28 + n_json:28 + n_json + n_bin]
    else:
        header = json.loads(data)
        blob = base64.b64decode(header["buffers"][0]["uri"].split(",", 1)[1])
    return header, blob


def accessor(header, blob, index):
    a = header["accessors"][index]
    view = header["bufferViews"][a["bufferView"]]
    dtype = {5126: np.float32, 5125: np.uint32}[a["componentType"]]
    width = {"VEC3": 3, "SCALAR": 1}[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    return np.frombuffer(blob, dtype=dtype, count=a["count"] * width, offset=start).reshape(
        a["count"], width)


def quaternion_matrix(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    t, r, s = np.eye(4), np.eye(4), np.eye(4)
    t[:3, 3] = node.get("translation", [0, 0, 0])
    r[:3, :3] = quaternion_matrix(*node.get("rotation", [0, 0, 0, 1]))
    s[:3, :3] = np.diag(node.get("scale", [1, 1, 1]))
    return t @ r @ s


def world_meshes(path):
    """{node name: (world vertices, triangles, material or None, node)} by hand."""
    header, blob = read_gltf(path)
    out = {}

    def visit(i, parent):
        node = header["nodes"][i]
        m = parent @ local_matrix(node)
        if "mesh" in node:
            (prim,) = header["meshes"][node["mesh"]]["primitives"]
            v = accessor(header, blob, prim["attributes"]["POSITION"]).astype(np.float64)
            t = accessor(header, blob, prim["indices"]).reshape(-1, 3).astype(np.int64)
            w = (m @ np.c_[v, np.ones(len(v))].T).T[:, :3]
            if np.linalg.det(m[:3, :3]) < 0:
                t = t[:, ::-1]
            mat = header["materials"][prim["material"]] if "material" in prim else None
            out[node["name"]] = (w, t, mat, node, m)
        for c in node.get("children", []):
            visit(c, m)

    for root in header["scenes"][header.get("scene", 0)]["nodes"]:
        visit(root, np.eye(4))
    return out


def normals(v, t):
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


# ---- the example room --------------------------------------------------------------------------


@pytest.fixture(params=[".glb", ".gltf"])
def example(tmp_path, request):
    path = write_example_room(tmp_path / f"room{request.param}")
    return path, load_room(path, EXAMPLE_PAINTINGS)


def test_vertices_are_numpy_matrix_products(example):
    path, spec = example
    ref = world_meshes(path)
    assert {s.name for s in spec.surfaces} == {"walls", "plinth", "light"}
    for s in spec.surfaces:
        v, t, mat, _, _ = ref[s.name]
        np.testing.assert_allclose(s.vertices, v, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(s.triangles, t)
        pbr = mat["pbrMetallicRoughness"]
        assert s.albedo == tuple(pbr["baseColorFactor"][:3])
        strength = mat.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get(
            "emissiveStrength", 1.0)
        assert s.emission == tuple(e * strength for e in mat.get("emissiveFactor", [0, 0, 0]))
    # the hierarchy really transforms: the plinth is rotated 20 + 45 degrees and scaled
    _, _, _, _, m = ref["plinth"]
    assert np.linalg.det(m[:3, :3]) == pytest.approx(0.5 * 0.8 * 0.5)
    # the light is under a mirroring node: glTF's winding rule makes it emit down
    light = next(s for s in spec.surfaces if s.name == "light")
    np.testing.assert_allclose(normals(light.vertices, light.triangles),
                               [[0, -1, 0]] * 2, atol=1e-12)
    assert light.emission == pytest.approx((6.0, 5.4, 4.8))


def test_camera_from_the_node_hierarchy(example):
    path, spec = example
    header, _ = read_gltf(path)
    m = local_matrix(header["nodes"][0]) @ local_matrix(header["nodes"][9])  # gallery, camera
    np.testing.assert_allclose(spec.camera_eye, m[:3, 3], atol=1e-12)
    np.testing.assert_allclose(np.subtract(spec.camera_target, spec.camera_eye), -m[:3, 2],
                               atol=1e-12)
    assert spec.name == "room"  # the file's stem: the example's scene has no name


def test_placeholders_become_slots(example):
    path, spec = example
    ref = world_meshes(path)
    slots = {s.name: s for s in spec.paintings}
    assert set(slots) == {"painting:landscape", "side placeholder"}
    assert slots["painting:landscape"].painting == "landscape"
    assert slots["side placeholder"].painting == 1  # from extras {"painting": 1}
    for name, slot in slots.items():
        v, t, _, _, m = ref[name]
        o, u, vv = (np.array(x) for x in (slot.origin, slot.u_axis, slot.v_axis))
        corners = np.array([o, o + u * slot.width_m, o + vv * slot.height_m,
                            o + u * slot.width_m + vv * slot.height_m])
        # the same four corners (any order)
        d = np.linalg.norm(corners[:, None] - v[None], axis=2)
        assert d.min(axis=1).max() < 1e-6
        # front = v x u is the transformed local +z (the placeholder's normal)
        front = m[:3, :3] @ [0, 0, 1]
        np.testing.assert_allclose(np.cross(vv, u), front / np.linalg.norm(front), atol=1e-6)
        np.testing.assert_allclose(normals(v, t), [front / np.linalg.norm(front)] * 2,
                                   atol=1e-6)
        key = slot.painting if isinstance(slot.painting, str) else list(EXAMPLE_PAINTINGS)[1]
        w, h = EXAMPLE_PAINTINGS[key]
        assert slot.width_m / slot.height_m == pytest.approx(w / h, rel=1e-6)
        assert slot.v_axis == pytest.approx((0, -1, 0))  # walls are vertical: image top up


def same_room(a, b, atol=0.0):
    assert [s.name for s in a.surfaces] == [s.name for s in b.surfaces]
    for x, y in zip(a.surfaces, b.surfaces):
        np.testing.assert_allclose(x.vertices, y.vertices, rtol=0, atol=atol)
        np.testing.assert_array_equal(x.triangles, y.triangles)
        assert x.albedo == pytest.approx(y.albedo, rel=1e-15)
        assert x.emission == pytest.approx(y.emission, rel=1e-15)
    assert len(a.paintings) == len(b.paintings)
    for x, y in zip(a.paintings, b.paintings):
        assert x.painting == y.painting
        for f in ("origin", "u_axis", "v_axis"):
            np.testing.assert_allclose(getattr(x, f), getattr(y, f), rtol=0, atol=atol + 1e-12)
        assert (x.width_m, x.height_m) == pytest.approx((y.width_m, y.height_m), abs=atol + 1e-12)


def test_obj_and_ply_give_the_gltf_room(tmp_path):
    ref = load_room(write_example_room(tmp_path / "room.glb"), EXAMPLE_PAINTINGS)
    for suffix in (".obj", ".ply", ".gltf"):
        other = load_room(write_example_room(tmp_path / f"room{suffix}"), EXAMPLE_PAINTINGS)
        same_room(ref, other)


def test_command_line(tmp_path, capsys):
    assert main([str(tmp_path / "r.glb")]) == 0
    assert (tmp_path / "r.glb").is_file()
    assert main([]) == 2
    assert main([str(tmp_path / "r.txt")]) == 2
    assert not list(tmp_path.glob("*.part"))


# ---- orientation with the project's camera -----------------------------------------------------


def rotation(axis, degrees):
    axis = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    h = math.radians(degrees) / 2
    return quaternion_matrix(*(axis * math.sin(h)), math.cos(h))


def placeholder_room(tmp_path, r, translation, aspect=2.0, extras=None, name="painting:p"):
    """A light plus one placeholder: local xy rectangle facing +z, rotated by r."""
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, translation
    v = np.array([[-aspect / 2, -0.5, 0], [aspect / 2, -0.5, 0], [aspect / 2, 0.5, 0],
                  [-aspect / 2, 0.5, 0]])
    nodes = [dict(name="lamp", vertices=[[0, 3, 0], [1, 3, 0], [0, 3, 1]], triangles=[[0, 2, 1]],
                  albedo=(0.5, 0.5, 0.5), emission=(1, 1, 1)),
             dict(name=name, matrix=m, vertices=v, triangles=[[0, 1, 2], [0, 2, 3]],
                  extras=extras)]
    return write_gltf(nodes, tmp_path / "p.glb")


@pytest.mark.parametrize("yaw", [0, 37, 90, 180, 271])
def test_image_reads_unmirrored_from_the_front_on_walls(tmp_path, yaw):
    r = rotation([0, 1, 0], yaw)
    spec = load_room(placeholder_room(tmp_path, r, [1, 1.5, -2]), {"p": 2.0})
    check_top_left_from_front(spec.paintings[0], r @ [0, 1, 0])


def test_image_orientation_with_extras_up(tmp_path):
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        r = quaternion_matrix(*q)
        up = r @ [0, 1, 0]
        path = placeholder_room(tmp_path, r, rng.uniform(-2, 2, 3),
                                extras={"painting": "p", "up": up.tolist()})
        check_top_left_from_front(load_room(path, {"p": 2.0}).paintings[0], up)


def test_horizontal_placeholder_top_towards_minus_z(tmp_path):
    # facing up, like the hall's paintings: v = +z, u = +x, as multi_exhibition places them
    r = rotation([1, 0, 0], -90)  # local +z -> +y
    (slot,) = load_room(placeholder_room(tmp_path, r, [0, 0.7, 0]), {"p": 2.0}).paintings
    np.testing.assert_allclose(slot.u_axis, [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(slot.v_axis, [0, 0, 1], atol=1e-12)


def check_top_left_from_front(slot, up):
    o, u, v = (np.array(x) for x in (slot.origin, slot.u_axis, slot.v_axis))
    centre = o + (u * slot.width_m + v * slot.height_m) / 2
    front = np.cross(v, u)
    cam = Camera(tuple(centre + 3 * front), tuple(centre), tuple(up), fov=60,
                 resolution=(400, 400))
    px = [cam.project(tuple(p)) for p in (o, o + u * slot.width_m, o + v * slot.height_m)]
    assert all(p is not None for p in px)
    (x0, y0), (x1, y1), (x2, y2) = px
    assert x1 > x0 + 50 and abs(y1 - y0) <= 1   # image x runs right on screen
    assert y2 > y0 + 50 and abs(x2 - x0) <= 1   # image y runs down on screen
    assert x0 < 200 and y0 < 200                # texel (0, 0) at the top-left


# ---- round trips -----------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".obj", ".ply"])
@pytest.mark.parametrize("room,count", [("scroll", None), ("hall", 16)])
def test_builtin_rooms_round_trip(tmp_path, suffix, room, count):
    spec = builtin_room(room, TABLE4_PAINTINGS, count)
    back = load_room(save_room(spec, tmp_path / f"{room}{suffix}"), TABLE4_PAINTINGS)
    # glTF stores positions as float32: within its rounding of a ~30 m room
    same_room(spec, back, atol=4e-6 if suffix in (".glb", ".gltf") else 1e-12)
    assert [s.name for s in back.surfaces] == [s.name for s in spec.surfaces]
    if suffix in (".glb", ".gltf"):  # the name and the camera too (OBJ / PLY have neither)
        assert back.name == spec.name == room
        np.testing.assert_allclose(back.camera_eye, spec.camera_eye, atol=1e-12)
        np.testing.assert_allclose(back.camera_target, spec.camera_target, atol=1e-12)
        # without the target hint the camera still looks the same way (down its -z)
        header, blob = read_gltf(tmp_path / f"{room}{suffix}")
        (cam,) = [n for n in header["nodes"] if "camera" in n]
        m = local_matrix(cam)
        d = np.subtract(spec.camera_target, spec.camera_eye)
        np.testing.assert_allclose(-m[:3, 2], d / np.linalg.norm(d), atol=1e-12)
        np.testing.assert_allclose(m[:3, 1] @ [0, 1, 0] > 0, True)
    assert ROOM_NAMES == ("scroll", "hall")


def test_scroll_slot_by_name_and_index(tmp_path):
    spec = builtin_room("scroll", [SCROLL])
    spec.paintings[0].painting = SCROLL.name
    back = load_room(save_room(spec, tmp_path / "s.glb"), TABLE4_PAINTINGS)
    assert back.paintings[0].painting == SCROLL.name


# ---- bad files -------------------------------------------------------------------------------


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(OSError, match="nope.glb"):
        load_room(tmp_path / "nope.glb", EXAMPLE_PAINTINGS)
    (tmp_path / "junk.glb").write_bytes(b"glTF" + bytes(100))
    with pytest.raises(ValueError, match="junk.glb"):
        load_room(tmp_path / "junk.glb", EXAMPLE_PAINTINGS)
    (tmp_path / "junk.gltf").write_text("{not json")
    with pytest.raises(ValueError, match="junk.gltf"):
        load_room(tmp_path / "junk.gltf", EXAMPLE_PAINTINGS)
    (tmp_path / "junk.ply").write_text("ply\nformat ascii 1.0\nend_header\n")
    with pytest.raises(ValueError, match="junk.ply"):
        load_room(tmp_path / "junk.ply", EXAMPLE_PAINTINGS)
    (tmp_path / "room.fbx").write_text("")
    with pytest.raises(ValueError, match="unknown room file type"):
        load_room(tmp_path / "room.fbx", EXAMPLE_PAINTINGS)


def base_nodes():
    return [dict(name="lamp", vertices=[[0, 3, 0], [1, 3, 0], [0, 3, 1]], triangles=[[0, 2, 1]],
                 albedo=(0.5, 0.5, 0.5), emission=(1, 1, 1)),
            dict(name="floor", vertices=[[0, 0, 0], [1, 0, 0], [0, 0, 1]],
                 triangles=[[0, 2, 1]], albedo=(0.3, 0.3, 0.3))]


def write(tmp_path, nodes, name="bad.glb"):
    return write_gltf(nodes, tmp_path / name)


@pytest.mark.parametrize("change,message", [
    (lambda n: n[1].update(albedo=(1.0, 0.5, 0.5)), "'floor'.*albedo"),
    (lambda n: n[1].update(albedo=(-0.1, 0.5, 0.5)), "'floor'.*albedo"),
    (lambda n: n[1].update(translation=[float("nan"), 0, 0]), "'floor'"),
    (lambda n: n[1].update(scale=[1e30, 1, 1]), "'floor'"),
    (lambda n: n[1].update(vertices=[[0, 0, 0], [1, float("inf"), 0], [0, 0, 1]]), "'floor'"),
    (lambda n: n[0].update(emission=(0, 0, 0)), "no light"),
    (lambda n: n.append(dict(name="painting:ghost", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0],
                                                              [0, 1, 0]],
                             triangles=[[0, 1, 2], [0, 2, 3]])), "'painting:ghost'.*ghost"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0.2],
                                                          [0, 1, 0]],
                             triangles=[[0, 1, 2], [0, 2, 3]])), "'painting:p'.*planar"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2.1, 0, 0], [2.1, 1, 0],
                                                          [0, 1, 0]],
                             triangles=[[0, 1, 2], [0, 2, 3]])), "'painting:p'.*aspect"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2.3, 1, 0],
                                                          [0.3, 1, 0]],
                             triangles=[[0, 1, 2], [0, 2, 3]])), "'painting:p'.*rectangle"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0],
                                                          [0, 1, 0], [1, 0.5, 0]],
                             triangles=[[0, 1, 4], [1, 2, 4], [2, 3, 4]])), "'painting:p'"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0],
                                                          [0, 1, 0]],
                             triangles=[[0, 1, 2], [0, 3, 2]])), "'painting:p'"),
    (lambda n: n.append(dict(name="painting:p", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0],
                                                          [0, 1, 0]],
                             triangles=[[0, 1, 2], [0, 1, 3]])), "'painting:p'.*cover"),
    (lambda n: n.append(dict(name="x", vertices=[[0, 0, 0], [2e-4, 0, 0], [2e-4, 1e-4, 0],
                                                 [0, 1e-4, 0]],
                             triangles=[[0, 1, 2], [0, 2, 3]], extras={"painting": 0})), "'x'"),
])
def test_bad_content_names_the_node(tmp_path, change, message):
    nodes = base_nodes()
    change(nodes)
    with pytest.raises(ValueError, match="bad.glb.*" + message):
        load_room(write(tmp_path, nodes), {"p": 2.0})


def test_aspect_within_one_percent_is_accepted(tmp_path):
    nodes = base_nodes() + [dict(name="painting:p", vertices=[[0, 0, 0], [2.018, 0, 0],
                                                              [2.018, 1, 0], [0, 1, 0]],
                                 triangles=[[0, 1, 2], [0, 2, 3]])]
    (slot,) = load_room(write(tmp_path, nodes), {"p": 2.0}).paintings
    assert slot.width_m == pytest.approx(2.018)
    # duplicated corner vertices (unwelded quads) are still one rectangle
    nodes[-1] = dict(name="painting:0", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 0, 0],
                                                  [2, 1, 0], [0, 1, 0]],
                     triangles=[[0, 1, 2], [3, 4, 5]])
    (slot,) = load_room(write(tmp_path, nodes), {"p": 2.0}).paintings
    assert slot.painting == 0 and slot.origin == pytest.approx((0, 1, 0))


def test_primitive_without_material(tmp_path):
    nodes = base_nodes()
    nodes[1]["albedo"] = None
    with pytest.raises(ValueError, match="'floor'.*no material"):
        load_room(write(tmp_path, nodes), {"p": 2.0})


def test_accepts_a_tile_pack(tmp_path):
    from gigascroll import TilePack, build_pack

    img = np.zeros((20, 40, 3), dtype=np.uint8)
    build_pack(img, tmp_path / "pack", tile_size=16, border=2)
    pack = TilePack(tmp_path / "pack")
    nodes = base_nodes() + [dict(name="painting:0", vertices=[[0, 0, 0], [2, 0, 0], [2, 1, 0],
                                                              [0, 1, 0]],
                                 triangles=[[0, 1, 2], [0, 2, 3]])]
    (slot,) = load_room(write(tmp_path, nodes), pack).paintings
    assert slot.painting in (0, pack.paintings[0].name)


def test_external_buffers(tmp_path):
    embedded = write_example_room(tmp_path / "e.gltf")
    header = json.loads(embedded.read_text())
    blob = base64.b64decode(header["buffers"][0]["uri"].split(",", 1)[1])
    (tmp_path / "e.bin").write_bytes(blob)
    header["buffers"][0]["uri"] = "e.bin"
    (tmp_path / "ext.gltf").write_text(json.dumps(header))
    same_room(load_room(embedded, EXAMPLE_PAINTINGS), load_room(tmp_path / "ext.gltf",
                                                                 EXAMPLE_PAINTINGS))
    for uri in ("missing.bin", "/dev/zero", "."):
        header["buffers"][0]["uri"] = uri
        (tmp_path / "bad.gltf").write_text(json.dumps(header))
        with pytest.raises(OSError, match="bad.gltf.*buffer 0"):
            load_room(tmp_path / "bad.gltf", EXAMPLE_PAINTINGS)


def test_obj_without_its_materials(tmp_path):
    obj = write_example_room(tmp_path / "room.obj")
    (tmp_path / "room.mtl").unlink()
    with pytest.raises(ValueError, match=r"room.obj: node '\w+' has no material"):
        load_room(obj, EXAMPLE_PAINTINGS)


def test_node_trees_only(tmp_path):
    lamp = base_nodes()[0]
    chain = [dict(name=f"n{i}", translation=[0.01, 0, 0], children=[i + 1]) for i in range(64)]
    spec = load_room(write(tmp_path, chain + [lamp]), {"p": 2.0})  # 64 levels deep: fine
    np.testing.assert_allclose(spec.surfaces[0].vertices[0], [0.64, 3, 0], atol=1e-9)
    chain = [dict(name=f"n{i}", children=[i + 1]) for i in range(65)]
    with pytest.raises(ValueError, match="bad.glb: node 65 is nested more than 64"):
        load_room(write(tmp_path, chain + [lamp]), {"p": 2.0})
    cycle = [dict(name="a", children=[1]), dict(lamp, children=[0])]
    with pytest.raises(ValueError, match="bad.glb.*cycle"):
        load_room(write_gltf(cycle, tmp_path / "bad.glb", roots=[0]), {"p": 2.0})
    two_parents = [dict(name="a", children=[2]), dict(name="b", children=[2]), lamp]
    with pytest.raises(ValueError, match="bad.glb: node 2 has two parents"):
        load_room(write(tmp_path, two_parents), {"p": 2.0})

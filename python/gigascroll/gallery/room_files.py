"""Rooms from files: glTF 2.0 (.gltf / .glb), OBJ (+ .mtl) and PLY, read through trimesh, as a
`RoomSpec`; and `save_room`, which writes a `RoomSpec` back as such a file.

Before trimesh reads anything, the file is checked from its structure: every file it names
is a regular file, read safely and only if used (room_assets); a glTF file follows the glTF 2.0
specification (its JSON Schema and the rules beyond it) and its drawn instances fit the
triangle budget, counted from the node graph and the accessors' counts (room_gltf); OBJ faces
and PLY elements are counted from the text. The budget is what the gallery can bake
(room_assets.MAX_TRIANGLES).

glTF: trimesh reads the geometry and the scene graph; every node's world transform (the
product of its ancestors' matrix / TRS) is applied to its vertices, and a node whose transform
mirrors (negative determinant) has its triangles' winding reversed, as glTF specifies, so
emission keeps facing the same way. Materials are read from the file's JSON (trimesh keeps
baseColorFactor only to 8 bits and drops KHR_materials_emissive_strength): albedo =
baseColorFactor (rgb; the alpha and any textures are ignored), emission radiance =
emissiveFactor x KHR_materials_emissive_strength (W / m^2 / sr per channel, linear; 1 when the
extension is absent). A primitive without a material is an error: glTF's default material is
white (albedo 1).

OBJ: one object (`o NAME`) per node, vertices already in world space (OBJ has no transforms);
its material from the .mtl next to it: Kd -> albedo, Ke -> emission (radiance, no clamping).
glTF light nodes: a node whose extras hold {"light": {"kelvin": K, "lumens": F}} or {"light":
{"kelvin": K, "lux": E, "painting": KEY}} is a `LightSpec` (gallery/lights.py): its triangles are
the panels (emitting toward their winding normal), its material gives the albedo, and its
emission is solved for the luminous flux F or for the mean direct illuminance E on the slot (or
painting) KEY; kelvin may be left out (white). Any emissiveFactor of the node is replaced.
A glTF file's first camera node gives the RoomSpec's camera: eye at the node's world position,
target from the node's extras {"target": [x, y, z]} or 1 m down its -z; the scene's name (else
the file's stem) names the room.

PLY (no scene graph, no materials): one file holds the whole room; the face property `surface`
(int) indexes an element `surface` with float properties albedo_r, albedo_g, albedo_b,
emission_r, emission_g, emission_b and a list of uchar `name` (UTF-8), one row per node.

Painting placeholders: a node named `painting:<key>` or whose glTF extras hold
{"painting": <key>} (key: a painting's name, or its index as an int or a decimal string). Its
mesh must be one planar rectangle: exactly four corners and two triangles that cover it, both
facing the same way. Its front is the side the triangles' normal points to (counter-clockwise
winding seen from the front). The image is placed so that it reads unmirrored from the front
with the project's camera (right = forward x up): texel (0, 0) is the top-left corner seen from
the front, u_axis (image x) runs to the right and v_axis (image y) down, so front = v x u.
"Up" is world +y projected into the placeholder's plane, or world -z for a placeholder within
~25 degrees of horizontal (a painting on a table reads with its top towards -z), or the vector
in extras {"up": [x, y, z]}; v_axis is the rectangle edge closest to down. The rectangle's
aspect (along u : along v) must be within 1 % of the painting's. A placeholder becomes a
PaintingSlot only (no Surface); the wall behind it is a node of its own.
"""

from __future__ import annotations

import base64
import io
import json
import math
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..outputs import write_bytes
from .lights import light_from_extras, light_surface
from .room import PaintingSlot, RoomSpec, Surface
from .room_assets import (MAX_FILE_BYTES, MAX_TRIANGLES, MAX_VERTICES,  # noqa: F401
                          check_regular, check_triangles, read_regular)
from .room_gltf import (MATERIAL_TAG, MAX_NODE_DEPTH, MAX_NODES, NODE_TAG,  # noqa: F401
                        check_gltf, list_of_dicts, read_gltf, trimesh_input)
from .sizes import PaintingSize, painting_sizes

__all__ = ["load_room", "save_room", "ROOM_FILE_SUFFIXES", "PAINTING_PREFIX"]

ROOM_FILE_SUFFIXES = (".glb", ".gltf", ".obj", ".ply")
PAINTING_PREFIX = "painting:"
MAX_EXTENT_M = 10_000.0        # every vertex within 10 km of the origin
MIN_PAINTING_M = 1e-3          # a placeholder's sides are at least 1 mm ...
MAX_RADIANCE = 1e9             # ... and no emitter is brighter than this (W / m^2 / sr)
ASPECT_TOLERANCE = 0.01
PLANAR_TOLERANCE = 1e-4        # relative to the placeholder's diagonal (float32 positions)
_GLB_MAGIC, _GLB_JSON, _GLB_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
_CAMERA = "gigascroll_camera"  # marks the camera pseudo-node between reader and assembly


@dataclass
class _Node:
    """One mesh instance of the file, in world space."""
    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    albedo: tuple | None = None
    emission: tuple = (0.0, 0.0, 0.0)
    extras: dict = field(default_factory=dict)


def load_room(path, paintings, name: str | None = None) -> RoomSpec:
    """The room in a .glb / .gltf / .obj / .ply file (see the module docstring).
    `paintings`: the pack's paintings (a TilePack, a list or a mapping; see `painting_sizes`),
    used to bind and check the placeholders. Bad files raise OSError (missing / unreadable) or
    ValueError (anything else), naming the file and the node."""
    path = Path(path)
    sizes = painting_sizes(paintings)
    suffix = path.suffix.lower()
    if suffix not in ROOM_FILE_SUFFIXES:
        raise ValueError(f"{path}: unknown room file type {suffix!r} (want one of "
                         f"{', '.join(ROOM_FILE_SUFFIXES)})")
    try:
        data = read_regular(path, f"{path}: room file", MAX_FILE_BYTES)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such room file") from None
    reader = {".glb": _gltf_nodes, ".gltf": _gltf_nodes, ".obj": _obj_nodes, ".ply": _ply_nodes}
    try:
        with np.errstate(all="ignore"):  # hostile transforms overflow inside trimesh; checked after
            nodes = reader[suffix](path, data)
    except (TypeError, KeyError, IndexError, AttributeError, OverflowError) as e:
        # a JSON value of the wrong shape that the checks above did not anticipate
        raise ValueError(f"{path}: malformed room file: {type(e).__name__}: {e}") from None
    spec = _room_from_nodes(path, nodes, sizes, path.stem)
    if name:
        spec.name = name
    return spec


# --- glTF --------------------------------------------------------------------------------------

def _gltf_material(header: dict, index, path: Path, node: str) -> tuple[tuple, tuple]:
    materials = list_of_dicts(header, "materials", path)
    if not isinstance(index, int) or not 0 <= index < len(materials):
        raise ValueError(f"{path}: node {node!r} has no material (glTF's default is white, "
                         f"albedo 1)")
    m = materials[index]
    pbr = m.get("pbrMetallicRoughness", {})
    base = pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0]) if isinstance(pbr, dict) else None
    emissive = m.get("emissiveFactor", [0.0, 0.0, 0.0])
    ext = m.get("extensions", {})
    strength = 1.0
    if isinstance(ext, dict) and isinstance(ext.get("KHR_materials_emissive_strength"), dict):
        strength = ext["KHR_materials_emissive_strength"].get("emissiveStrength", 1.0)
    albedo = _numbers(base, 4, path, node, "baseColorFactor")[:3]
    emission = tuple(e * _numbers([strength], 1, path, node, "emissiveStrength")[0]
                     for e in _numbers(emissive, 3, path, node, "emissiveFactor"))
    return albedo, emission


def _numbers(values, n: int, path: Path, node: str, what: str, text: bool = False) -> tuple:
    """n finite numbers (JSON numbers; decimal strings only where the format is text: OBJ)."""
    try:
        if isinstance(values, (str, bytes)) or any(
                isinstance(x, bool) or isinstance(x, (str, bytes)) != text for x in values):
            raise TypeError
        out = tuple(float(x) for x in values)
        if len(out) != n:
            raise TypeError
    except (TypeError, ValueError):
        raise ValueError(f"{path}: node {node!r}: {what} must be {n} numbers, got "
                         f"{values!r}") from None
    if not all(math.isfinite(x) for x in out):
        raise ValueError(f"{path}: node {node!r}: {what} is not finite: {values!r}")
    return out


def _gltf_nodes(path: Path, data: bytes) -> list[_Node]:
    """The drawn mesh instances of a glTF file, checked first (room_gltf) and then read by
    trimesh from what room_gltf hands it (the drawn meshes' positions and indices only)."""
    import trimesh

    header, binary = read_gltf(path, data)
    drawn = check_gltf(header, path)
    nodes = header.get("nodes", [])
    names = [n["name"] if isinstance(n.get("name"), str) else f"node{i}"
             for i, n in enumerate(nodes)]
    for i, n in enumerate(nodes):
        for k in ("matrix", "translation", "rotation", "scale"):
            if k in n:
                _numbers(n[k], {"matrix": 16, "translation": 3, "rotation": 4, "scale": 3}[k],
                         path, names[i], k)
    text, files = trimesh_input(header, binary, path, drawn)
    try:
        scene = trimesh.load(io.BytesIO(text), file_type="gltf", resolver=files, force="scene",
                             process=False)
    except OSError:
        raise
    except Exception as e:  # trimesh raises anything from KeyError to AssertionError
        raise ValueError(f"{path}: trimesh cannot read it: {type(e).__name__}: {e}") from None
    out = [(-1, _gltf_camera(header, path))]
    for frame in scene.graph.nodes_geometry:
        matrix, geometry_name = scene.graph[frame]
        geometry = scene.geometry.get(geometry_name)
        if not isinstance(geometry, trimesh.Trimesh):
            continue  # lines and points are not surfaces
        forest = scene.graph.transforms
        edge = forest.edge_data.get((forest.parents.get(frame), frame), {})
        meta = edge.get("metadata") or forest.node_data.get(frame, {}).get("metadata") or {}
        index = meta.get(NODE_TAG)
        if not isinstance(index, int):
            raise ValueError(f"{path}: cannot trace trimesh node {frame!r} back to the file")
        extras = nodes[index].get("extras")
        material = getattr(getattr(geometry.visual, "material", None), "name", None)
        material_index = (int(material[len(MATERIAL_TAG):]) if isinstance(material, str)
                          and material.startswith(MATERIAL_TAG) else None)
        vertices, triangles = _transformed(path, names[index], matrix, geometry)
        node = _Node(names[index], vertices, triangles,
                     extras=extras if isinstance(extras, dict) else {})
        if _placeholder_key(node) is None:
            node.albedo, node.emission = _gltf_material(header, material_index, path,
                                                        names[index])
        out.append((index, node))
    return [node for _, node in sorted(out, key=lambda item: item[0]) if node is not None]


def _local_matrix(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    x, y, z, w = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
    rotation = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = rotation * np.asarray(node.get("scale", [1.0, 1.0, 1.0]), dtype=np.float64)
    m[:3, 3] = node.get("translation", [0.0, 0.0, 0.0])
    return m


def _gltf_camera(header: dict, path: Path):
    """The first camera node as a _Node without geometry carrying extras eye / target (or
    None): eye at its world position, target from extras "target" or 1 m down its -z."""
    nodes = header.get("nodes", [])
    parent = {}
    for i, n in enumerate(nodes):
        for c in n.get("children", []) if isinstance(n.get("children"), list) else []:
            if isinstance(c, int):
                parent.setdefault(c, i)
    for i, n in enumerate(nodes):
        if "camera" not in n:
            continue
        m, j, seen = np.eye(4), i, set()
        while j is not None and j not in seen and 0 <= j < len(nodes):
            seen.add(j)
            m = _local_matrix(nodes[j]) @ m
            j = parent.get(j)
        eye = m[:3, 3]
        extras = n.get("extras") if isinstance(n.get("extras"), dict) else {}
        target = (np.array(_numbers(extras["target"], 3, path, "camera", "extras.target"))
                  if "target" in extras else eye - m[:3, 2] / max(np.linalg.norm(m[:3, 2]), 1e-300))
        if not (np.isfinite(eye).all() and np.isfinite(target).all()):
            raise ValueError(f"{path}: camera node {n.get('name', i)!r} has a non-finite transform")
        return _Node("camera", np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                     extras={"eye": tuple(map(float, eye)), "target": tuple(map(float, target)),
                             _CAMERA: True, "scene": _scene_name(header)})
    return _Node("camera", np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                 extras={_CAMERA: True, "scene": _scene_name(header)})


def _scene_name(header: dict):
    scenes = header.get("scenes")
    index = header.get("scene", 0)
    if isinstance(scenes, list) and isinstance(index, int) and 0 <= index < len(scenes) \
            and isinstance(scenes[index], dict) and isinstance(scenes[index].get("name"), str):
        return scenes[index]["name"]
    return None


def _transformed(path: Path, name: str, matrix, geometry) -> tuple[np.ndarray, np.ndarray]:
    m = np.asarray(matrix, dtype=np.float64)
    if not np.isfinite(m).all():
        raise ValueError(f"{path}: node {name!r} has a non-finite transform")
    v = np.asarray(geometry.vertices, dtype=np.float64)
    f = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
    if not np.isfinite(v).all():
        raise ValueError(f"{path}: node {name!r} has non-finite vertices")
    with np.errstate(all="ignore"):
        world = v @ m[:3, :3].T + m[:3, 3]
    if not np.isfinite(world).all() or (len(world) and np.abs(world).max() > MAX_EXTENT_M):
        raise ValueError(f"{path}: node {name!r} reaches beyond {MAX_EXTENT_M:g} m "
                         f"(absurd size or transform)")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"{path}: node {name!r} has triangle indices out of range")
    used, local = np.unique(f, return_inverse=True)  # drop vertices no triangle uses
    world, f = world[used], local.reshape(-1, 3).astype(np.int64)
    if np.linalg.det(m[:3, :3]) < 0:
        f = f[:, ::-1].copy()  # a mirroring transform flips the winding (glTF 2.0, 3.7.4)
    return world, f


def _glb_bytes(text: bytes, binary: bytes | None) -> bytes:
    text = text + b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), _GLB_JSON) + text
    if binary is not None:
        binary = binary + b"\0" * (-len(binary) % 4)
        chunks += struct.pack("<II", len(binary), _GLB_BIN) + binary
    return struct.pack("<III", _GLB_MAGIC, 2, 12 + len(chunks)) + chunks


# --- OBJ and PLY -------------------------------------------------------------------------------

class _Files(dict):
    """The files trimesh may ask a loader's resolver for, read beforehand: a name missing here
    is not opened on demand. file_name: the room file's name (trimesh names an unnamed OBJ
    object after it)."""
    file_name = None


_MTL_MAPS = ("map_", "bump", "disp", "decal", "refl", "norm")  # texture statements of an MTL


def _parse_mtl(text: str, lib: Path, room: Path) -> dict[str, dict]:
    """newmtl / Kd / Ke of an .mtl file, at full precision. The texture maps it names are
    never read (the gallery uses Kd and Ke), but each must be a regular file or missing."""
    materials, current = {}, None
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "newmtl" and len(parts) >= 2:
            current = materials.setdefault(" ".join(parts[1:]), {})
        elif parts[0] in ("Kd", "Ke") and current is not None:
            current[parts[0]] = parts[1:]
        elif parts[0].lower().startswith(_MTL_MAPS) and len(parts) >= 2:
            image = lib.parent / parts[-1]  # options (-s 1 1 1 ...) come before the file
            check_regular(image, f"{room}: {lib.name}: {parts[0]} file {parts[-1]!r}",
                          missing_ok=True)
    return materials


def _obj_libraries(path: Path, text: str) -> tuple[dict, _Files, dict]:
    """The materials of every mtllib the OBJ names (read safely; a missing one gives none),
    those files for trimesh's resolver, and the objects' order in the file."""
    mtl, files, objects = {}, _Files(), {}
    files.file_name = path.name
    for line in text.splitlines():
        if line.startswith("mtllib") and len(line.split(maxsplit=1)) == 2:
            name = line.split(maxsplit=1)[1].strip()
            lib = path.parent / name
            what = f"{path}: mtllib {name!r}"
            if name in files or check_regular(lib, what, missing_ok=True) is None:
                continue
            data = read_regular(lib, what, MAX_FILE_BYTES)
            files[name] = data
            mtl.update(_parse_mtl(data.decode("utf-8", errors="replace"), lib, path))
        elif line.startswith("o ") and len(line.split(maxsplit=1)) == 2:
            objects.setdefault(line.split(maxsplit=1)[1].strip(), len(objects))
    return mtl, files, objects


def _count_obj_faces(path: Path, text: str):
    """The OBJ's triangles (a face of k corners is k - 2), before trimesh expands them."""
    triangles = 0
    for line in text.splitlines():
        if line.startswith("f ") or line.startswith("f\t"):
            triangles += max(len(line.split()) - 3, 0)
    check_triangles(path, triangles)


def _obj_nodes(path: Path, data: bytes) -> list[_Node]:
    import trimesh

    text = data.decode("utf-8", errors="replace")
    _count_obj_faces(path, text)
    mtl, files, objects = _obj_libraries(path, text)
    try:
        scene = trimesh.load(io.BytesIO(data), file_type="obj", resolver=files, force="scene",
                             process=False, split_objects=True, group_material=True,
                             maintain_order=True)
    except OSError:
        raise
    except Exception as e:
        raise ValueError(f"{path}: trimesh cannot read it: {type(e).__name__}: {e}") from None
    out, order = [], list(scene.geometry)
    for frame in scene.graph.nodes_geometry:
        matrix, geometry_name = scene.graph[frame]
        geometry = scene.geometry[geometry_name]
        if not isinstance(geometry, trimesh.Trimesh):
            continue
        material = getattr(getattr(geometry.visual, "material", None), "name", None)
        name = _obj_object_name(geometry_name, material, mtl)
        vertices, triangles = _transformed(path, name, matrix, geometry)
        node = _Node(name, vertices, triangles)
        if _placeholder_key(node) is None:
            if material not in mtl:
                raise ValueError(f"{path}: node {name!r} has no material in the .mtl")
            m = mtl[material]
            node.albedo = _numbers(m.get("Kd", ["1", "1", "1"])[:3], 3, path, name, "Kd", True)
            node.emission = _numbers(m.get("Ke", ["0", "0", "0"])[:3], 3, path, name, "Ke", True)
        out.append((objects.get(name, len(objects) + order.index(geometry_name)), node))
    return [node for _, node in sorted(out, key=lambda item: item[0])]  # file order


def _obj_object_name(geometry_name: str, material, mtl) -> str:
    """trimesh names an object's geometry OBJECT or OBJECT_MATERIAL (several materials)."""
    if isinstance(material, str) and len(mtl) > 1 and geometry_name.endswith("_" + material):
        return geometry_name[:-len(material) - 1]
    return geometry_name


def _check_ply_header(path: Path, data: bytes):
    """The PLY header's element counts within the budget, before trimesh allocates them (a
    face has at least one triangle)."""
    end = data.find(b"end_header", 0, 1 << 20)
    for line in data[:end if end >= 0 else 1 << 20].decode("ascii", "replace").splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0] == "element" and parts[2].isdigit():
            count = int(parts[2])
            if parts[1] == "face":
                check_triangles(path, count, " (faces)")
            elif count > MAX_VERTICES:
                raise ValueError(f"{path}: {count} {parts[1]} elements, more than {MAX_VERTICES}")


def _ply_nodes(path: Path, data: bytes) -> list[_Node]:
    import trimesh

    _check_ply_header(path, data)
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type="ply", force="mesh", process=False)
        raw = mesh.metadata.get("_ply_raw", {})
        surface_of_face = np.asarray(raw["face"]["data"]["surface"], dtype=np.int64).reshape(-1)
        table = raw["surface"]["data"]
        rows = len(table["name"])
        columns = {k: np.asarray(table[k]) for k in ("albedo_r", "albedo_g", "albedo_b",
                                                       "emission_r", "emission_g", "emission_b")}
        names = [bytes(np.asarray(n, dtype=np.uint8)).decode("utf-8") for n in table["name"]]
    except OSError:
        raise
    except Exception as e:
        raise ValueError(f"{path}: trimesh cannot read it as a gigascroll PLY room (face "
                         f"property 'surface' and element 'surface'): {type(e).__name__}: "
                         f"{e}") from None
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if len(surface_of_face) != len(faces) or (len(faces) and (
            surface_of_face.min() < 0 or surface_of_face.max() >= rows)):
        raise ValueError(f"{path}: face property 'surface' out of range")
    vertices, _ = _transformed(path, path.name, np.eye(4), mesh)
    out = []
    for s in range(rows):
        tri = faces[surface_of_face == s]
        used, local = np.unique(tri, return_inverse=True)
        node = _Node(names[s], vertices[used], local.reshape(-1, 3).astype(np.int64))
        if _placeholder_key(node) is None:
            node.albedo = _numbers([columns[f"albedo_{c}"][s] for c in "rgb"], 3, path,
                                   names[s], "albedo")
            node.emission = _numbers([columns[f"emission_{c}"][s] for c in "rgb"], 3, path,
                                     names[s], "emission")
        out.append(node)
    return out


# --- nodes -> RoomSpec -------------------------------------------------------------------------

def _placeholder_key(node: _Node):
    """The painting key of a placeholder node (str or int), or None."""
    if "painting" in node.extras:
        return node.extras["painting"]
    if node.name.startswith(PAINTING_PREFIX):
        return node.name[len(PAINTING_PREFIX):]
    return None


def _resolve_painting(key, sizes: list[PaintingSize], path: Path, node: str) -> int | str:
    """A painting name, else a decimal index; `name#tag` names one of several placeholders
    of the same painting (node names must be unique in OBJ and PLY)."""
    if isinstance(key, str):
        for k in (key, key.rpartition("#")[0]) if "#" in key else (key,):
            if any(p.name == k for p in sizes):
                return k
            if k.isdigit() and int(k) < len(sizes):
                return int(k)
    elif isinstance(key, int) and not isinstance(key, bool) and 0 <= key < len(sizes):
        return key
    raise ValueError(f"{path}: placeholder {node!r}: no painting {key!r} among the "
                     f"{len(sizes)} paintings ({', '.join(p.name for p in sizes[:8])}"
                     f"{', ...' if len(sizes) > 8 else ''})")


def _slot(node: _Node, sizes: list[PaintingSize], path: Path) -> PaintingSlot:
    key = _resolve_painting(_placeholder_key(node), sizes, path, node.name)
    painting = sizes[key] if isinstance(key, int) else next(p for p in sizes if p.name == key)
    what = f"{path}: placeholder {node.name!r}"
    v, f = node.vertices, node.triangles
    if len(f) != 2:
        raise ValueError(f"{what} must be one rectangle of two triangles, has {len(f)}")
    scale = float(np.ptp(v[f.reshape(-1)], axis=0).max()) if len(v) else 0.0
    if not scale > 0:
        raise ValueError(f"{what} is degenerate (zero size)")
    # Corners: the triangles' vertices, merged within a tolerance (files may duplicate them).
    corners = []
    for p in v[f.reshape(-1)]:
        if not any(np.linalg.norm(p - c) <= PLANAR_TOLERANCE * scale for c in corners):
            corners.append(p)
    if len(corners) != 4:
        raise ValueError(f"{what} must have exactly four corners, has {len(corners)}")
    t = v[f]
    normals = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    areas = np.linalg.norm(normals, axis=1)
    if areas.min() <= (PLANAR_TOLERANCE * scale) ** 2:
        raise ValueError(f"{what} has a degenerate triangle")
    if np.dot(normals[0], normals[1]) <= 0:
        raise ValueError(f"{what}: its two triangles face opposite ways")
    n = normals.sum(axis=0)
    n /= np.linalg.norm(n)
    corners = np.array(corners)
    centre = corners.mean(axis=0)
    if np.abs((corners - centre) @ n).max() > PLANAR_TOLERANCE * scale or \
            (normals / areas[:, None] @ n).min() < 1 - 1e-6:
        raise ValueError(f"{what} is not planar (or its two triangles face opposite ways)")
    # A rectangle: the corners' centroid is the midpoint of both diagonals, which are equal.
    order = np.argsort(np.arctan2(*((corners - centre) @ _plane_basis(n)).T[::-1]))
    c = corners[order]
    diagonals = (np.linalg.norm(c[2] - c[0]), np.linalg.norm(c[3] - c[1]))
    e1, e2 = c[1] - c[0], c[3] - c[0]
    if abs(diagonals[0] - diagonals[1]) > PLANAR_TOLERANCE * scale or \
            np.linalg.norm(c[0] + c[2] - c[1] - c[3]) > PLANAR_TOLERANCE * scale or \
            abs(np.dot(e1, e2)) > PLANAR_TOLERANCE * scale * scale:
        raise ValueError(f"{what} is not a rectangle")
    # Cover it: the triangles' corners (in c's counter-clockwise order) share one diagonal.
    corner_of = [int(np.argmin(np.linalg.norm(c - p, axis=1))) for p in v[f.reshape(-1)]]
    a, b = set(corner_of[:3]), set(corner_of[3:])
    shared = sorted(a & b)
    if len(a) != 3 or len(b) != 3 or len(shared) != 2 or shared[1] - shared[0] != 2 or \
            abs(areas.sum() / 2 - np.linalg.norm(e1) * np.linalg.norm(e2)) > \
            1e-3 * areas.sum() / 2:
        raise ValueError(f"{what}: its two triangles do not cover the rectangle")
    up = _up_of(node, n, path)
    down = -(up - np.dot(up, n) * n)
    edges = [e / np.linalg.norm(e) for e in (e1, e2)]
    v_axis = max((s * e for e in edges for s in (1.0, -1.0)), key=lambda d: np.dot(d, down))
    u_axis = np.cross(n, v_axis)
    coords = (c - centre) @ np.stack([u_axis, v_axis]).T
    origin = c[np.argmin(coords[:, 0] + coords[:, 1])]
    width, height = float(np.ptp(coords[:, 0])), float(np.ptp(coords[:, 1]))
    if min(width, height) < MIN_PAINTING_M:
        raise ValueError(f"{what} is {width:.3g} m x {height:.3g} m, smaller than "
                         f"{MIN_PAINTING_M * 1000:g} mm")
    aspect = width / height
    if abs(aspect / painting.aspect - 1) > ASPECT_TOLERANCE:
        raise ValueError(f"{what}: aspect {aspect:.5g} (width along u / height along v, "
                         f"{width:.4g} m x {height:.4g} m) differs from painting "
                         f"{painting.name!r}'s {painting.aspect:.5g} by more than "
                         f"{ASPECT_TOLERANCE:.0%}")
    return PaintingSlot(key, tuple(float(x) for x in origin), tuple(float(x) for x in u_axis),
                        tuple(float(x) for x in v_axis), width, height, name=node.name)


def _plane_basis(n: np.ndarray) -> np.ndarray:
    a = np.eye(3)[np.argmin(np.abs(n))]
    x = np.cross(n, a)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(n, x)]).T


def _up_of(node: _Node, n: np.ndarray, path: Path) -> np.ndarray:
    if "up" in node.extras:
        up = np.array(_numbers(node.extras["up"], 3, path, node.name, "extras.up"))
        if np.linalg.norm(up - np.dot(up, n) * n) < 1e-6 * max(np.linalg.norm(up), 1e-300):
            raise ValueError(f"{path}: placeholder {node.name!r}: extras.up is along its normal")
        return up / np.linalg.norm(up)
    world_up = np.array([0.0, 1.0, 0.0])
    if abs(n[1]) > math.cos(math.radians(25.0)):
        return np.array([0.0, 0.0, -1.0])
    return world_up


def _room_from_nodes(path: Path, nodes: list[_Node], sizes, name: str) -> RoomSpec:
    surfaces, slots, light_nodes = [], [], []
    total = 0
    used_names = set()
    eye = target = None
    for node in nodes:
        if node.extras.get(_CAMERA) is True and len(node.triangles) == 0:
            eye, target = node.extras.get("eye"), node.extras.get("target")
            name = node.extras.get("scene") or name
            continue
        total += len(node.triangles)
        check_triangles(path, total)
        if _placeholder_key(node) is not None:
            slots.append(_slot(node, sizes, path))
            continue
        if len(node.triangles) == 0:
            continue
        if "light" in node.extras:
            light_nodes.append(node)
            continue
        albedo, emission = node.albedo, node.emission
        if not all(0 <= a < 1 for a in albedo):
            raise ValueError(f"{path}: node {node.name!r}: albedo {albedo} must be in [0, 1) "
                             f"per channel (>= 1 creates energy)")
        if not all(0 <= e <= MAX_RADIANCE for e in emission):
            raise ValueError(f"{path}: node {node.name!r}: emission {emission} must be in "
                             f"[0, {MAX_RADIANCE:g}] W/m^2/sr")
        surface_name = node.name
        k = 1
        while surface_name in used_names:
            surface_name, k = f"{node.name}#{k}", k + 1
        used_names.add(surface_name)
        surfaces.append(Surface(surface_name, np.ascontiguousarray(node.vertices),
                                np.ascontiguousarray(node.triangles), tuple(albedo),
                                tuple(emission)))
    lights = _lights(path, light_nodes, slots, used_names)
    surfaces += [surface for _, surface in lights]
    if not any(max(s.emission) > 0 for s in surfaces):
        raise ValueError(f"{path}: the room has no light (no node with emission > 0)")
    return RoomSpec(name, surfaces, slots, camera_eye=eye, camera_target=target,
                    lights=[light for light, _ in lights])


def _lights(path: Path, nodes: list[_Node], slots: list[PaintingSlot], used_names: set) -> list:
    """(LightSpec, its Surface) of each light node (extras "light"), solved once every
    painting slot is known."""
    result = []
    for node in nodes:
        if not all(0 <= a < 1 for a in node.albedo):
            raise ValueError(f"{path}: node {node.name!r}: albedo {node.albedo} must be in "
                             f"[0, 1) per channel (>= 1 creates energy)")
        name, k = node.name, 1
        while name in used_names:
            name, k = f"{node.name}#{k}", k + 1
        used_names.add(name)
        try:
            light = light_from_extras(name, list(node.vertices[node.triangles]),
                                      node.extras["light"], node.albedo)
            result.append((light, light_surface(light, slots)))
        except ValueError as e:
            raise ValueError(f"{path}: {e}") from None
    return result


# --- writing -----------------------------------------------------------------------------------

def save_room(spec: RoomSpec, path) -> Path:
    """Write a RoomSpec as .glb / .gltf (one node per surface and per painting slot, exact
    factors, KHR_materials_emissive_strength for radiance above 1), .obj (+ .mtl beside it) or
    .ply, so that load_room gives it back (positions are float32 in glTF, as the format is).
    Placeholders are written as rectangles facing v x u with extras {"painting", "up"}; OBJ and
    PLY carry no extras, so their slots follow the default "up" rule."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".glb", ".gltf"):
        nodes = [dict(name=s.name, vertices=s.vertices, triangles=s.triangles,
                      albedo=s.albedo, emission=s.emission) for s in spec.surfaces]
        for slot in spec.paintings:
            nodes.append(dict(name=slot.name or f"{PAINTING_PREFIX}{slot.painting}",
                              vertices=_slot_corners(slot), triangles=_QUAD,
                              extras={"painting": slot.painting,
                                      "up": [-x for x in slot.v_axis]}))
        if spec.camera_eye is not None and spec.camera_target is not None:
            nodes.append(dict(name="camera", matrix=_look_at_matrix(spec.camera_eye,
                                                                    spec.camera_target),
                              camera={"type": "perspective",
                                      "perspective": {"yfov": math.radians(60.0),
                                                      "znear": 0.01}},
                              extras={"target": [float(x) for x in spec.camera_target]}))
        write_gltf(nodes, path, scene_name=spec.name)
    elif suffix == ".obj":
        _write_obj(spec, path)
    elif suffix == ".ply":
        _write_ply(spec, path)
    else:
        raise ValueError(f"{path}: unknown room file type {suffix!r}")
    return path


_QUAD = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)


def _look_at_matrix(eye, target) -> np.ndarray:
    """A glTF camera node's transform: at eye, looking down -z towards target, y up."""
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    back = eye - target
    back /= np.linalg.norm(back)
    up = np.array([0.0, 1.0, 0.0]) if abs(back[1]) < 0.999 else np.array([0.0, 0.0, -1.0])
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, np.cross(back, right), back, eye
    return m


def _slot_corners(slot: PaintingSlot) -> np.ndarray:
    """Top-left, bottom-left, bottom-right, top-right: counter-clockwise seen from v x u."""
    o, u, v = (np.asarray(x, dtype=np.float64) for x in (slot.origin, slot.u_axis, slot.v_axis))
    u, v = u * slot.width_m, v * slot.height_m
    return np.array([o, o + v, o + u + v, o + u])


def write_gltf(nodes: list[dict], path, roots: list[int] | None = None,
               scene_name: str | None = None) -> Path:
    """Write nodes as a glTF 2.0 file (.glb, or .gltf with the buffer embedded as a data URI).
    Each node: name, optional vertices (n, 3) + triangles (m, 3) with albedo / emission (or
    extras marking a placeholder), optional matrix (4 x 4, row-major numpy convention) or
    translation / rotation (xyzw) / scale, optional children (node indices), optional extras,
    optional camera (a glTF camera object; the camera looks down its node's -z).
    `roots`: the scene's root nodes (default: nodes nobody lists as a child)."""
    path = Path(path)
    blob = bytearray()
    header = {"asset": {"version": "2.0", "generator": "gigascroll.gallery"},
              "scene": 0, "nodes": [], "meshes": [], "materials": [], "accessors": [],
              "bufferViews": []}
    uses_strength = False

    def add_view(data: bytes, target: int) -> int:
        blob.extend(b"\0" * (-len(blob) % 4))
        header["bufferViews"].append({"buffer": 0, "byteOffset": len(blob),
                                      "byteLength": len(data), "target": target})
        blob.extend(data)
        return len(header["bufferViews"]) - 1

    children_of_someone = set()
    for node in nodes:
        out = {"name": node["name"]}
        for key in ("translation", "rotation", "scale"):
            if key in node:
                out[key] = [float(x) for x in node[key]]
        if "matrix" in node:
            out["matrix"] = [float(x) for x in np.asarray(node["matrix"], dtype=np.float64).T.ravel()]
        if node.get("children"):
            out["children"] = [int(c) for c in node["children"]]
            children_of_someone.update(out["children"])
        if node.get("extras"):
            out["extras"] = node["extras"]
        if node.get("camera"):
            header.setdefault("cameras", []).append(node["camera"])
            out["camera"] = len(header["cameras"]) - 1
        if node.get("vertices") is not None:
            v = np.ascontiguousarray(node["vertices"], dtype=np.float32)
            t = np.ascontiguousarray(node["triangles"], dtype=np.uint32)
            pos = add_view(v.tobytes(), 34962)
            idx = add_view(t.tobytes(), 34963)
            header["accessors"].append({"bufferView": pos, "componentType": 5126,
                                        "count": len(v), "type": "VEC3",
                                        "min": v.min(axis=0).tolist(),
                                        "max": v.max(axis=0).tolist()})
            header["accessors"].append({"bufferView": idx, "componentType": 5125,
                                        "count": t.size, "type": "SCALAR"})
            primitive = {"attributes": {"POSITION": len(header["accessors"]) - 2},
                         "indices": len(header["accessors"]) - 1, "mode": 4}
            if node.get("albedo") is not None:
                material = {"name": node["name"],
                            "pbrMetallicRoughness": {
                                "baseColorFactor": [float(a) for a in node["albedo"]] + [1.0],
                                "metallicFactor": 0.0, "roughnessFactor": 1.0},
                            "doubleSided": True}
                emission = [float(e) for e in node.get("emission", (0.0, 0.0, 0.0))]
                peak = max(emission)
                if peak > 0:
                    if peak > 1:
                        material["emissiveFactor"] = [e / peak for e in emission]
                        material["extensions"] = {
                            "KHR_materials_emissive_strength": {"emissiveStrength": peak}}
                        uses_strength = True
                    else:
                        material["emissiveFactor"] = emission
                header["materials"].append(material)
                primitive["material"] = len(header["materials"]) - 1
            header["meshes"].append({"name": node["name"], "primitives": [primitive]})
            out["mesh"] = len(header["meshes"]) - 1
        header["nodes"].append(out)
    if roots is None:
        roots = [i for i in range(len(nodes)) if i not in children_of_someone]
    header["scenes"] = [{"nodes": list(roots)} if roots else {}]
    if scene_name:
        header["scenes"][0]["name"] = scene_name
    if uses_strength:
        header["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    blob.extend(b"\0" * (-len(blob) % 4))
    header["buffers"] = [{"byteLength": len(blob)}]
    for key in ("nodes", "meshes", "materials", "accessors", "bufferViews", "buffers"):
        if not header[key] or not blob and key == "buffers":  # the schema: non-empty, or none
            del header[key]
    if path.suffix.lower() == ".glb":
        data = _glb_bytes(json.dumps(header).encode("utf-8"), bytes(blob) if blob else None)
    else:
        if blob:
            header["buffers"][0]["uri"] = ("data:application/octet-stream;base64,"
                                           + base64.b64encode(bytes(blob)).decode("ascii"))
        data = json.dumps(header, indent=1).encode("utf-8")
    _write_whole(path, data)
    return path


def _write_whole(path: Path, data: bytes):
    """Write to a temporary name and rename (outputs.write_bytes): a half-written file never
    looks complete, and a failed write leaves no temporary behind."""
    write_bytes(path, data)


def _surfaces_and_placeholders(spec: RoomSpec):
    items = [(s.name, s.vertices, s.triangles, s.albedo, s.emission) for s in spec.surfaces]
    keys = [str(slot.painting) for slot in spec.paintings]
    for i, (slot, key) in enumerate(zip(spec.paintings, keys)):
        tag = f"#{i}" if keys.count(key) > 1 or "#" in key else ""
        items.append((f"{PAINTING_PREFIX}{key}{tag}", _slot_corners(slot), _QUAD, None, None))
    names = [i[0] for i in items]
    if len(set(names)) != len(names) or any(not n or any(ch.isspace() for ch in n)
                                            for n in names):
        raise ValueError("OBJ / PLY rooms need unique node names without spaces (placeholders "
                         "are named painting:<key>)")
    return items


def _write_obj(spec: RoomSpec, path: Path):
    items = _surfaces_and_placeholders(spec)
    mtl_path = path.with_suffix(".mtl")
    obj, mtl = [f"mtllib {mtl_path.name}"], []
    base = 1
    for name, v, t, albedo, emission in items:
        obj.append(f"o {name}")
        obj.append(f"usemtl {name}")
        mtl.append(f"newmtl {name}")
        if albedo is not None:
            mtl.append("Kd " + " ".join(repr(float(a)) for a in albedo))
            mtl.append("Ke " + " ".join(repr(float(e)) for e in emission))
        else:
            mtl.append("Kd 0.5 0.5 0.5")
        obj += ["v " + " ".join(repr(float(x)) for x in p) for p in np.asarray(v)]
        obj += [f"f {a + base} {b + base} {c + base}" for a, b, c in np.asarray(t)]
        base += len(v)
    _write_whole(mtl_path, ("\n".join(mtl) + "\n").encode("utf-8"))
    try:
        _write_whole(path, ("\n".join(obj) + "\n").encode("utf-8"))
    except OSError:
        mtl_path.unlink(missing_ok=True)  # no half a room: the .mtl goes with its .obj
        raise


def _write_ply(spec: RoomSpec, path: Path):
    items = _surfaces_and_placeholders(spec)
    vertices = np.concatenate([np.asarray(i[1], dtype=np.float64) for i in items])
    faces, surface, base = [], [], 0
    for k, (_, v, t, _, _) in enumerate(items):
        faces.append(np.asarray(t, dtype=np.int64) + base)
        surface += [k] * len(t)
        base += len(v)
    faces = np.concatenate(faces)
    lines = ["ply", "format ascii 1.0", "comment gigascroll room (see gallery/room_files.py)",
             f"element vertex {len(vertices)}", "property double x", "property double y",
             "property double z", f"element face {len(faces)}",
             "property list uchar int vertex_indices", "property int surface",
             f"element surface {len(items)}"]
    lines += [f"property double {c}" for c in ("albedo_r", "albedo_g", "albedo_b",
                                                "emission_r", "emission_g", "emission_b")]
    lines += ["property list uchar uchar name", "end_header"]
    lines += [" ".join(repr(float(x)) for x in p) for p in vertices]
    lines += [f"3 {a} {b} {c} {s}" for (a, b, c), s in zip(faces, surface)]
    for name, _, _, albedo, emission in items:
        values = list(albedo or (0.5, 0.5, 0.5)) + list(emission or (0.0, 0.0, 0.0))
        raw = name.encode("utf-8")
        if len(raw) > 255:
            raise ValueError(f"node name {name!r} is too long for PLY")
        lines.append(" ".join(repr(float(x)) for x in values) + f" {len(raw)} "
                     + " ".join(str(b) for b in raw))
    _write_whole(path, ("\n".join(lines) + "\n").encode("ascii"))

"""A glTF 2.0 room file (.gltf / .glb) as `Node`s: the file is checked from its structure
first (gltf.py: the JSON Schema, the rules beyond it, the triangle budget), then trimesh reads
the drawn meshes from what gltf.py hands it. Every node's world transform (the product of its
ancestors' matrix / TRS) is applied to its vertices, and a node whose transform mirrors has
its triangles' winding reversed, as glTF specifies, so emission keeps facing the same way.
Materials are read from the file's JSON (trimesh keeps baseColorFactor only to 8 bits and drops
KHR_materials_emissive_strength): albedo = baseColorFactor (rgb; the alpha and any textures are
ignored), emission radiance = emissiveFactor x KHR_materials_emissive_strength (W / m^2 / sr per
channel, linear; 1 when the extension is absent). A primitive without a material is an error:
glTF's default material is white (albedo 1). The first camera node gives the room's camera: eye
at the node's world position, target from its extras {"target": [x, y, z]} or 1 m down its -z;
the scene's name (else the file's stem) names the room.
"""

from __future__ import annotations

import io
import struct
from pathlib import Path

import numpy as np

from .gltf import MATERIAL_TAG, NODE_TAG, check_gltf, list_of_dicts, read_gltf, trimesh_input
from .nodes import CAMERA_MARK, GLB_BIN, GLB_JSON, GLB_MAGIC, Node, finite_numbers, world_mesh
from .placeholders import placeholder_key

__all__ = ["gltf_nodes", "glb_bytes"]


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
    albedo = finite_numbers(base, 4, path, node, "baseColorFactor")[:3]
    emission = tuple(e * finite_numbers([strength], 1, path, node, "emissiveStrength")[0]
                     for e in finite_numbers(emissive, 3, path, node, "emissiveFactor"))
    return albedo, emission


def gltf_nodes(path: Path, data: bytes) -> list[Node]:
    """The drawn mesh instances of a glTF file, checked first (room/gltf.py) and then read by
    trimesh from what room/gltf.py hands it (the drawn meshes' positions and indices only)."""
    import trimesh

    header, binary = read_gltf(path, data)
    drawn = check_gltf(header, path)
    nodes = header.get("nodes", [])
    names = [n["name"] if isinstance(n.get("name"), str) else f"node{i}"
             for i, n in enumerate(nodes)]
    for i, n in enumerate(nodes):
        for k in ("matrix", "translation", "rotation", "scale"):
            if k in n:
                finite_numbers(n[k], {"matrix": 16, "translation": 3, "rotation": 4, "scale": 3}[k],
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
        vertices, triangles = world_mesh(path, names[index], matrix, geometry)
        node = Node(names[index], vertices, triangles,
                     extras=extras if isinstance(extras, dict) else {})
        if placeholder_key(node) is None:
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
    """The first camera node as a Node without geometry carrying extras eye / target (or
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
        target = (np.array(finite_numbers(extras["target"], 3, path, "camera", "extras.target"))
                  if "target" in extras else eye - m[:3, 2] / max(np.linalg.norm(m[:3, 2]), 1e-300))
        if not (np.isfinite(eye).all() and np.isfinite(target).all()):
            raise ValueError(f"{path}: camera node {n.get('name', i)!r} has a non-finite transform")
        return Node("camera", np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                     extras={"eye": tuple(map(float, eye)), "target": tuple(map(float, target)),
                             CAMERA_MARK: True, "scene": _scene_name(header)})
    return Node("camera", np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                 extras={CAMERA_MARK: True, "scene": _scene_name(header)})


def _scene_name(header: dict):
    scenes = header.get("scenes")
    index = header.get("scene", 0)
    if isinstance(scenes, list) and isinstance(index, int) and 0 <= index < len(scenes) \
            and isinstance(scenes[index], dict) and isinstance(scenes[index].get("name"), str):
        return scenes[index]["name"]
    return None


def glb_bytes(text: bytes, binary: bytes | None) -> bytes:
    text = text + b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), GLB_JSON) + text
    if binary is not None:
        binary = binary + b"\0" * (-len(binary) % 4)
        chunks += struct.pack("<II", len(binary), GLB_BIN) + binary
    return struct.pack("<III", GLB_MAGIC, 2, 12 + len(chunks)) + chunks

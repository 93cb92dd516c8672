"""`save_room`: a `RoomSpec` written back as a room file (.glb / .gltf, .obj + .mtl, .ply) that
`load_room` reads back; `write_gltf`, the glTF writer it and the example room use.
"""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path

import numpy as np

from ..outputs import write_bytes
from .gltf_nodes import glb_bytes
from .nodes import PAINTING_PREFIX
from .spec import PaintingSlot, RoomSpec

__all__ = ["save_room", "write_gltf"]


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
        data = glb_bytes(json.dumps(header).encode("utf-8"), bytes(blob) if blob else None)
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
    lines = ["ply", "format ascii 1.0", "comment gigascroll room (see room/files.py)",
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

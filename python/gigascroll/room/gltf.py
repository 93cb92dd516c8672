"""A glTF 2.0 room file checked before any of its geometry is read, and handed to trimesh
with only what the room uses.

The checks, in order, all on the JSON (and the sizes it declares):
  - the glTF 2.0 JSON Schema (the Khronos schema that trimesh ships, checked with
    jsonschema): types (a number given as a string is an error), ranges (byteStride a
    multiple of 4 in [4, 252]), required properties;
  - what the specification requires beyond the schema: every index names an existing object
    (a node's mesh and camera, a primitive's accessors and material, a scene's nodes); a node's
    matrix has the bottom row [0, 0, 0, 1] and no TRS beside it; POSITION is float VEC3;
    indices are an unsigned byte / short / int SCALAR from a view without byteStride; a view's
    byteStride holds the element of every accessor that strides it; every extension in
    extensionsRequired is one this reader implements;
  - every accessor within its view and every view within its buffer (a hostile count would
    otherwise ask for terabytes); nodes form trees of bounded depth;
  - the budget: the triangles and vertices of every mesh instance the scene draws, counted
    from the accessors' counts times the instances in the node graph, within what the
    gallery can bake, before any instance is expanded;
  - every file the room names is a regular file (room/assets.py).

Then only the buffers that the drawn meshes' POSITION and indices accessors read are read
(safely, and only the bytes they declare); images, textures, skins, animations and other
attributes are left out of what trimesh sees, so an unused file is never opened."""

from __future__ import annotations

import copy
import json
import struct
from pathlib import Path

from .assets import (MAX_FILE_BYTES, MAX_VERTICES, check_regular, check_triangles,
                          read_regular)

__all__ = ["read_gltf", "check_gltf", "trimesh_input", "list_of_dicts", "NODE_TAG",
           "MATERIAL_TAG", "SUPPORTED_EXTENSIONS"]

MAX_NODES = 20_000              # trimesh takes ~1 ms per node
MAX_NODE_DEPTH = 64            # glTF node nesting (trimesh's graph is quadratic in it)
# Extensions this reader implements (a file may require only these).
SUPPORTED_EXTENSIONS = frozenset({"KHR_materials_emissive_strength"})
NODE_TAG = "gigascroll_node"    # extras key that tags each node before trimesh reads the file
MATERIAL_TAG = "gigascroll-material-"
_GLB_MAGIC, _GLB_JSON, _GLB_BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
_COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
_TYPE_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INDEX_TYPES = (5121, 5123, 5125)
_TRIANGLES, _STRIP, _FAN = 4, 5, 6


def read_gltf(path: Path, data: bytes) -> tuple[dict, bytes | None]:
    """The JSON of a .gltf or .glb file (its bytes `data`) and a .glb's binary chunk."""
    binary = None
    try:
        if path.suffix.lower() == ".glb":
            if len(data) < 20:
                raise ValueError("too short for a GLB header")
            magic, version, length = struct.unpack_from("<III", data, 0)
            if magic != _GLB_MAGIC or version != 2:
                raise ValueError("not a glTF 2.0 binary (bad magic or version)")
            if length > len(data):
                raise ValueError(f"header says {length} bytes, file has {len(data)}")
            text, offset = None, 12
            while offset + 8 <= length:
                chunk_length, chunk_type = struct.unpack_from("<II", data, offset)
                chunk = data[offset + 8:offset + 8 + chunk_length]
                if len(chunk) != chunk_length:
                    raise ValueError("truncated chunk")
                if chunk_type == _GLB_JSON and text is None:
                    text = chunk
                elif chunk_type == _GLB_BIN and binary is None:
                    binary = chunk
                offset += 8 + chunk_length
            if text is None:
                raise ValueError("no JSON chunk")
        else:
            text = data
        header = json.loads(text.decode("utf-8"))
    except (ValueError, UnicodeDecodeError, struct.error, RecursionError) as e:
        raise ValueError(f"{path}: trimesh cannot read it as glTF: {e}") from None
    if not isinstance(header, dict):
        raise ValueError(f"{path}: glTF JSON is not an object")
    return header, binary


def list_of_dicts(header: dict, key: str, path: Path) -> list:
    items = header.get(key, [])
    if not isinstance(items, list) or not all(isinstance(x, dict) for x in items):
        raise ValueError(f"{path}: glTF '{key}' must be a list of objects")
    return items


def check_gltf(header: dict, path: Path) -> list[int]:
    """All the checks of the module docstring but the files'; returns the nodes the scene
    draws (each once: nodes form trees)."""
    for key in ("nodes", "meshes", "materials", "accessors", "bufferViews", "buffers",
                "scenes", "cameras", "images"):
        list_of_dicts(header, key, path)
    nodes = header.get("nodes", [])
    if len(nodes) > MAX_NODES:  # before the schema, whose check is ~0.1 ms per node
        raise ValueError(f"{path}: {len(nodes)} glTF nodes, more than {MAX_NODES}")
    _validate_schema(header, path)
    _check_extensions(header, path)
    _check_nodes(header, path)
    _check_primitives(header, path)
    _check_accessors(header, path)
    _check_node_tree(header, path)
    drawn = _drawn_nodes(header, path)
    _check_budget(header, drawn, path)
    return drawn


def _validate_schema(header: dict, path: Path):
    import jsonschema
    from trimesh.exchange.gltf import validate

    try:
        validate(header)
    except jsonschema.ValidationError as e:
        parts = list(e.absolute_path)
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in parts)
        message = " ".join(e.message.split())
        if e.validator == "not":  # the schema's way to forbid properties together
            message = ("a matrix beside translation, rotation or scale (glTF allows one or the "
                       "other)" if parts[:1] == ["nodes"] else "properties glTF forbids together")
        if len(message) > 200:
            message = message[:200] + " ..."
        label = next((f"{_LABELS[p]} " for p in parts if p in _LABELS), "")
        raise ValueError(f"{path}: {_users(header, parts)}{label}{where.lstrip('.') or 'the JSON'}"
                         f": {message} (not valid glTF 2.0: its JSON Schema)") from None


# What a material property is to the gallery, for the schema's messages.
_LABELS = {"baseColorFactor": "albedo", "emissiveFactor": "emission",
           "KHR_materials_emissive_strength": "emission"}


def _users(header: dict, parts: list) -> str:
    """'node NAME: ' for a schema error inside a node, or inside a mesh or material that a
    node uses (the first such node), else ''."""
    if len(parts) < 2 or not isinstance(parts[1], int):
        return ""
    nodes = header.get("nodes", []) if isinstance(header.get("nodes"), list) else []
    meshes = header.get("meshes", []) if isinstance(header.get("meshes"), list) else []

    def uses(n, i):
        if not isinstance(n, dict):
            return False
        if parts[0] == "nodes":
            return n is nodes[i]
        mesh = n.get("mesh")
        if not isinstance(mesh, int) or not 0 <= mesh < len(meshes):
            return False
        if parts[0] == "meshes":
            return mesh == i
        primitives = meshes[mesh].get("primitives") if isinstance(meshes[mesh], dict) else None
        return parts[0] == "materials" and isinstance(primitives, list) and any(
            isinstance(p, dict) and p.get("material") == i for p in primitives)

    for k, n in enumerate(nodes):
        if parts[0] in ("nodes", "meshes", "materials") and uses(n, parts[1]):
            name = n.get("name") if isinstance(n.get("name"), str) else f"node{k}"
            return f"node {name!r}: "
    return ""


def _check_extensions(header: dict, path: Path):
    unknown = sorted(set(header.get("extensionsRequired", [])) - SUPPORTED_EXTENSIONS)
    if unknown:
        raise ValueError(f"{path}: the file requires glTF extensions this reader does not "
                         f"implement: {', '.join(map(repr, unknown))} (it implements "
                         f"{', '.join(sorted(SUPPORTED_EXTENSIONS))})")


def _node_name(header: dict, i: int) -> str:
    n = header["nodes"][i]
    return n["name"] if isinstance(n.get("name"), str) else f"node{i}"


def _check_nodes(header: dict, path: Path):
    """Indices that name existing objects, and matrices that are affine (glTF 2.0 5.25: a
    matrix must decompose to TRS, so its bottom row is [0, 0, 0, 1], and TRS may not be given
    beside it)."""
    counts = {k: len(header.get(k, [])) for k in ("meshes", "cameras", "skins")}
    for i, n in enumerate(header.get("nodes", [])):
        name = _node_name(header, i)
        for key, of in (("mesh", "meshes"), ("camera", "cameras"), ("skin", "skins")):
            if key in n and not n[key] < counts[of]:
                raise ValueError(f"{path}: node {name!r}: its {key} {n[key]} is not among the "
                                 f"file's {counts[of]} {of}")
        if "matrix" in n:
            m = n["matrix"]  # column-major: the bottom row is elements 3, 7, 11, 15
            if [m[3], m[7], m[11], m[15]] != [0, 0, 0, 1]:
                raise ValueError(f"{path}: node {name!r}: matrix bottom row "
                                 f"{[m[3], m[7], m[11], m[15]]} is not [0, 0, 0, 1] "
                                 f"(glTF matrices are affine)")
            if any(k in n for k in ("translation", "rotation", "scale")):
                raise ValueError(f"{path}: node {name!r} has both a matrix and TRS")
    scenes = header.get("scenes", [])
    if "scene" in header and not header["scene"] < len(scenes):
        raise ValueError(f"{path}: scene {header['scene']} is not among the file's "
                         f"{len(scenes)} scenes")
    for s, scene in enumerate(scenes):
        for r in scene.get("nodes", []):
            if not r < len(header.get("nodes", [])):
                raise ValueError(f"{path}: scene {s} names node {r}, which does not exist")


def _check_primitives(header: dict, path: Path):
    accessors, views = header.get("accessors", []), header.get("bufferViews", [])
    materials = len(header.get("materials", []))
    for m, mesh in enumerate(header.get("meshes", [])):
        for k, p in enumerate(mesh["primitives"]):
            what = f"{path}: mesh {m} ({mesh.get('name', '')!r}) primitive {k}"
            named = list(p["attributes"].values()) + ([p["indices"]] if "indices" in p else [])
            for t in p.get("targets", []):
                named += list(t.values())
            if any(not a < len(accessors) for a in named):
                raise ValueError(f"{what} names an accessor that does not exist")
            if "material" in p and not p["material"] < materials:
                raise ValueError(f"{what} names material {p['material']}, which does not exist")
            if p.get("mode", _TRIANGLES) not in (_TRIANGLES, _STRIP, _FAN):
                continue  # points and lines: not surfaces, not read
            if "POSITION" not in p["attributes"]:
                raise ValueError(f"{what}: triangles without POSITION")
            a = accessors[p["attributes"]["POSITION"]]
            if a["type"] != "VEC3" or a["componentType"] != 5126:
                raise ValueError(f"{what}: POSITION must be float VEC3, is "
                                 f"{a['type']} of component type {a['componentType']}")
            if "indices" in p:
                a = accessors[p["indices"]]
                if a["type"] != "SCALAR" or a["componentType"] not in _INDEX_TYPES:
                    raise ValueError(f"{what}: indices must be an unsigned byte, short or int "
                                     f"SCALAR, are {a['type']} of component type "
                                     f"{a['componentType']}")
                view = a.get("bufferView", len(views))
                if view < len(views) and "byteStride" in views[view]:
                    raise ValueError(f"{what}: the indices' buffer view has a byteStride "
                                     f"(glTF forbids it)")


def _check_accessors(header: dict, path: Path):
    """Every accessor within its buffer view and every view within its buffer, before trimesh
    allocates anything (a hostile count would otherwise ask for terabytes)."""
    buffers, views = header.get("buffers", []), header.get("bufferViews", [])

    def integer(x, what):
        if isinstance(x, bool) or not isinstance(x, int) or not 0 <= x <= MAX_FILE_BYTES:
            raise ValueError(f"{path}: glTF {what} must be an integer in [0, {MAX_FILE_BYTES}], "
                             f"got {x!r}")
        return x

    for i, v in enumerate(views):
        b = integer(v.get("buffer", -1), f"bufferViews[{i}].buffer")
        if b >= len(buffers):
            raise ValueError(f"{path}: glTF bufferViews[{i}] names a missing buffer")
        end = integer(v.get("byteOffset", 0), "byteOffset") + integer(v.get("byteLength", -1),
                                                                        "byteLength")
        if end > integer(buffers[b].get("byteLength", -1), f"buffers[{b}].byteLength"):
            raise ValueError(f"{path}: glTF bufferViews[{i}] runs past its buffer")
    for i, a in enumerate(header.get("accessors", [])):
        size, width = _COMPONENT_BYTES[a["componentType"]], _TYPE_WIDTH[a["type"]]
        nbytes = integer(a.get("count", -1), f"accessors[{i}].count") * size * width
        if "sparse" in a:
            raise ValueError(f"{path}: glTF accessors[{i}]: sparse accessors are not supported")
        if "bufferView" not in a:  # all zeros (sparse is refused): no reason to be large
            if nbytes > 1 << 20:
                raise ValueError(f"{path}: glTF accessors[{i}] has no buffer view and "
                                 f"{a['count']} elements")
            continue
        view = integer(a["bufferView"], f"accessors[{i}].bufferView")
        if view >= len(views):
            raise ValueError(f"{path}: glTF accessors[{i}] names a missing buffer view")
        stride = integer(views[view].get("byteStride", size * width),
                         f"bufferViews[{view}].byteStride")
        if stride < size * width:
            raise ValueError(f"{path}: glTF bufferViews[{view}].byteStride {stride} is smaller "
                             f"than accessors[{i}]'s element ({size * width} bytes)")
        need = integer(a.get("byteOffset", 0), "byteOffset") + (
            0 if nbytes == 0 else stride * (nbytes // (size * width) - 1) + size * width)
        if need > views[view].get("byteLength", 0):
            raise ValueError(f"{path}: glTF accessors[{i}] runs past its buffer view")


def _check_node_tree(header: dict, path: Path):
    """glTF nodes form trees (one parent at most, no cycles); and a bounded depth, since
    trimesh's scene graph slows down quadratically with it (a hostile file could stall us)."""
    nodes = header.get("nodes", [])
    parent = {}
    for i, n in enumerate(nodes):
        for c in n.get("children", []):
            if not c < len(nodes):
                raise ValueError(f"{path}: node {i} has a child {c!r} that is not a node")
            if c in parent or c == i:
                raise ValueError(f"{path}: node {c} has two parents or is its own child "
                                 f"(glTF nodes form trees)")
            parent[c] = i
    for i in range(len(nodes)):
        depth, j = 0, i
        while j in parent:
            j, depth = parent[j], depth + 1
            if depth > MAX_NODE_DEPTH:
                raise ValueError(f"{path}: node {i} is nested more than {MAX_NODE_DEPTH} deep "
                                 f"(or in a cycle)")
    for s, scene in enumerate(header.get("scenes", [])):
        for r in scene.get("nodes", []):
            if r in parent:
                raise ValueError(f"{path}: scene {s} lists node {r} as a root, but it is the "
                                 f"child of node {parent[r]}")


def _drawn_nodes(header: dict, path: Path) -> list[int]:
    """The nodes the scene draws, as trimesh reads it: the roots of `scene` (default the first)
    and their descendants; none without scenes."""
    scenes = header.get("scenes", [])
    if not scenes:
        return []
    nodes = header.get("nodes", [])
    stack, drawn = list(scenes[header.get("scene", 0)].get("nodes", [])), []
    while stack:
        i = stack.pop()
        drawn.append(i)
        stack.extend(nodes[i].get("children", []))
    return sorted(drawn)


def _mesh_size(header: dict, mesh: dict) -> tuple[int, int]:
    """(triangles, vertices) of one instance of a mesh, from its accessors' counts."""
    accessors = header["accessors"]
    triangles = vertices = 0
    for p in mesh["primitives"]:
        mode = p.get("mode", _TRIANGLES)
        if mode not in (_TRIANGLES, _STRIP, _FAN):
            continue
        n = accessors[p["attributes"]["POSITION"]]["count"]
        k = accessors[p["indices"]]["count"] if "indices" in p else n
        triangles += k // 3 if mode == _TRIANGLES else max(k - 2, 0)
        vertices += n
    return triangles, vertices


def _check_budget(header: dict, drawn: list[int], path: Path):
    """The drawn instances' triangles and vertices, before any of them is expanded: within
    what the gallery can bake (assets.MAX_TRIANGLES)."""
    meshes, nodes = header.get("meshes", []), header.get("nodes", [])
    sizes = [_mesh_size(header, m) for m in meshes]
    instances = [nodes[i]["mesh"] for i in drawn if "mesh" in nodes[i]]
    triangles = sum(sizes[m][0] for m in instances)
    vertices = sum(sizes[m][1] for m in instances)
    check_triangles(path, triangles, f" drawn ({len(instances)} mesh instances)")
    if vertices > MAX_VERTICES:
        raise ValueError(f"{path}: the scene's {len(instances)} mesh instances have {vertices} "
                         f"vertices in all, more than {MAX_VERTICES}")


def trimesh_input(header: dict, binary: bytes | None, path: Path,
                  drawn: list[int]) -> tuple[bytes, dict]:
    """The glTF JSON that trimesh reads and the buffers it may ask for by name: the drawn
    meshes' POSITION and indices only (their accessors, views and buffers renumbered), every
    node tagged with its index (extras[NODE_TAG]) and every material named by its index
    (MATERIAL_TAG), no images, textures, skins or animations. The buffers used are read
    safely, only the bytes they declare; every other file the room names is checked to be a
    regular file (or missing) and never opened."""
    nodes = header.get("nodes", [])
    meshes = sorted({nodes[i]["mesh"] for i in drawn if "mesh" in nodes[i]})
    mesh_map = {m: k for k, m in enumerate(meshes)}
    out_meshes, used = [], {}
    for m in meshes:
        primitives = []
        for p in header["meshes"][m]["primitives"]:
            q = {"attributes": {}, "mode": p.get("mode", _TRIANGLES)}
            for key in ("POSITION",):
                if key in p["attributes"]:
                    q["attributes"][key] = used.setdefault(p["attributes"][key], len(used))
            if "indices" in p:
                q["indices"] = used.setdefault(p["indices"], len(used))
            if "material" in p:
                q["material"] = p["material"]
            primitives.append(q)
        out_meshes.append({"name": header["meshes"][m].get("name", f"mesh{m}"),
                           "primitives": primitives})
    accessors = [dict(header["accessors"][a]) for a in sorted(used, key=used.get)]
    views = sorted({a["bufferView"] for a in accessors if "bufferView" in a})
    view_map = {v: k for k, v in enumerate(views)}
    for a in accessors:
        a.pop("min", None), a.pop("max", None)
        if "bufferView" in a:
            a["bufferView"] = view_map[a["bufferView"]]
    out_views = [dict(header["bufferViews"][v]) for v in views]
    buffers = sorted({v["buffer"] for v in out_views})
    buffer_map = {b: k for k, b in enumerate(buffers)}
    for v in out_views:
        v["buffer"] = buffer_map[v["buffer"]]
    files, out_buffers = {}, []
    for b in buffers:
        name, data = _buffer_bytes(header, binary, b, path)
        if data is not None:
            files[name] = data
        out_buffers.append({"byteLength": header["buffers"][b]["byteLength"], "uri": name})
    _check_unused_files(header, set(buffers), path)
    out_nodes = []
    for i, n in enumerate(nodes):
        q = {k: copy.deepcopy(n[k]) for k in ("name", "children", "matrix", "translation",
                                                 "rotation", "scale", "camera") if k in n}
        if n.get("mesh") in mesh_map:
            q["mesh"] = mesh_map[n["mesh"]]
        q["extras"] = {NODE_TAG: i}
        out_nodes.append(q)
    tagged = {"asset": {"version": "2.0"}, "nodes": out_nodes, "meshes": out_meshes,
              "materials": [{"name": f"{MATERIAL_TAG}{i}"}
                            for i in range(len(header.get("materials", [])))],
              "accessors": accessors, "bufferViews": out_views, "buffers": out_buffers}
    for key in ("scene", "scenes", "cameras"):
        if key in header:
            tagged[key] = header[key]
    return json.dumps(tagged).encode("utf-8"), files


def _buffer_bytes(header: dict, binary: bytes | None, b: int, path: Path):
    """(the name trimesh reads buffer b by, its bytes or None for a data URI that trimesh
    decodes itself)."""
    buffer = header["buffers"][b]
    length, uri = buffer["byteLength"], buffer.get("uri")
    if uri is None:
        if b != 0 or binary is None:
            raise ValueError(f"{path}: buffer {b} has no uri (only a .glb's first buffer, its "
                             f"binary chunk, may omit it)")
        if len(binary) < length:
            raise ValueError(f"{path}: the binary chunk has {len(binary)} bytes, buffer 0 "
                             f"declares {length}")
        return f"gigascroll-buffer-{b}", binary[:length]
    if uri.startswith("data:"):
        if ";base64," not in uri:
            raise ValueError(f"{path}: buffer {b}: only base64 data URIs are supported")
        return uri, None
    data = read_regular(path.parent / uri, f"{path}: buffer {b} file {uri!r}", MAX_FILE_BYTES,
                        length=length)
    return f"gigascroll-buffer-{b}", data


def _check_unused_files(header: dict, used_buffers: set, path: Path):
    """Files the room names but does not read: regular files or missing, never opened."""
    named = [(f"buffer {b}", x.get("uri")) for b, x in enumerate(header.get("buffers", []))
             if b not in used_buffers]
    named += [(f"image {i}", x.get("uri")) for i, x in enumerate(header.get("images", []))]
    for what, uri in named:
        if isinstance(uri, str) and not uri.startswith("data:"):
            check_regular(path.parent / uri, f"{path}: {what} file {uri!r}", missing_ok=True)

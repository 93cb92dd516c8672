"""An OBJ room file (+ the .mtl libraries it names) as `Node`s: one object (`o NAME`) per
node, vertices already in world space (OBJ has no transforms); its material from the .mtl:
Kd -> albedo, Ke -> emission (radiance, no clamping). The faces are counted from the text and
every library is read (regular files only, room/assets.py) before trimesh sees any of it.
"""

from __future__ import annotations

import io
from pathlib import Path

from .assets import MAX_FILE_BYTES, check_regular, check_triangles, read_regular
from .nodes import Node, finite_numbers, world_mesh
from .placeholders import placeholder_key

__all__ = ["obj_nodes"]


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


def obj_nodes(path: Path, data: bytes) -> list[Node]:
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
        vertices, triangles = world_mesh(path, name, matrix, geometry)
        node = Node(name, vertices, triangles)
        if placeholder_key(node) is None:
            if material not in mtl:
                raise ValueError(f"{path}: node {name!r} has no material in the .mtl")
            m = mtl[material]
            node.albedo = finite_numbers(m.get("Kd", ["1", "1", "1"])[:3], 3, path, name, "Kd", True)
            node.emission = finite_numbers(m.get("Ke", ["0", "0", "0"])[:3], 3, path, name, "Ke", True)
        out.append((objects.get(name, len(objects) + order.index(geometry_name)), node))
    return [node for _, node in sorted(out, key=lambda item: item[0])]  # file order


def _obj_object_name(geometry_name: str, material, mtl) -> str:
    """trimesh names an object's geometry OBJECT or OBJECT_MATERIAL (several materials)."""
    if isinstance(material, str) and len(mtl) > 1 and geometry_name.endswith("_" + material):
        return geometry_name[:-len(material) - 1]
    return geometry_name

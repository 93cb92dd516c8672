"""The baked room as glTF 2.0 binary (docs/serve-protocol.md, "The room as glTF 2.0 binary").

Each room triangle's bake lattice of n segments becomes n^2 sub-triangles whose vertices are
the lattice points, carrying the baked irradiance of both sides as `_IRRADIANCE_FRONT` and
`_IRRADIANCE_BACK`: interpolating them linearly across a sub-triangle is exactly the core's
`lattice_lerp` (the lower cell (i, j), (i+1, j), (i, j+1) and the upper one (i+1, j+1),
(i, j+1), (i+1, j) of cpp/display/baked_lattice.h's `lattice_cell`). One mesh per room
surface and per painting slot (an Embree geometry of the gallery), in room coordinates.
Everything is built with numpy per lattice size, never per point."""

from __future__ import annotations

import json
import struct
from functools import lru_cache

import numpy as np

__all__ = ["lattice_template", "room_glb"]

GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942
FLOAT, UINT32 = 5126, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


@lru_cache(maxsize=64)
def lattice_template(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One triangle's lattice of n segments: (i, j) of each point in the core's order
    (lattice_index(i, j, n) = i (n + 1) - i (i - 1) / 2 + j) and the n^2 sub-triangles as
    point indices (n^2, 3), lower cells first, each wound as the triangle (v0, v0+e1, v0+e2)."""
    i, j = np.divmod(np.arange((n + 1) ** 2), n + 1)
    keep = i + j <= n
    i, j = i[keep], j[keep]

    def index(a, b):
        return a * (n + 1) - a * (a - 1) // 2 + b

    ci, cj = i[i + j <= n - 1], j[i + j <= n - 1]
    lower = np.stack([index(ci, cj), index(ci + 1, cj), index(ci, cj + 1)], axis=1)
    ui, uj = i[i + j <= n - 2], j[i + j <= n - 2]
    upper = np.stack([index(ui + 1, uj + 1), index(ui, uj + 1), index(ui + 1, uj)], axis=1)
    for a in (i, j):
        a.setflags(write=False)
    tris = np.concatenate([lower, upper]).astype(np.uint32)
    tris.setflags(write=False)
    return i, j, tris


def _mesh_arrays(lattice: dict, tris: np.ndarray) -> dict:
    """Vertices (positions, irradiance front and back) and sub-triangle indices of the room
    triangles `tris` (indices into the lattice arrays), grouped by lattice size."""
    pos, front, back, index = [], [], [], []
    origin = np.asarray(lattice.get("origin", (0.0, 0.0, 0.0)), np.float64)
    base = 0
    seg = lattice["segments"]
    for n in np.unique(seg[tris]):
        group = tris[seg[tris] == n]
        i, j, sub = lattice_template(int(n))
        k = len(i)
        s1 = (i.astype(np.float32) / np.float32(n))[None, :, None]
        s2 = (j.astype(np.float32) / np.float32(n))[None, :, None]
        # The core's point: v0 + e1 (i / n) + e2 (j / n), in float, around the room's origin.
        p = (lattice["v0"][group][:, None, :] + lattice["e1"][group][:, None, :] * s1
             + lattice["e2"][group][:, None, :] * s2)
        if np.any(origin):
            p = p + origin
        points = (lattice["offset"][group].astype(np.int64)[:, None] + np.arange(k)[None, :]).ravel()
        pos.append(p.reshape(-1, 3))
        front.append(lattice["front"][points])
        back.append(lattice["back"][points])
        index.append((sub[None, :, :] + (base + k * np.arange(len(group), dtype=np.uint32))[:, None, None]
                      ).reshape(-1, 3))
        base += k * len(group)
    return {"POSITION": np.concatenate(pos).astype(np.float32),
            "_IRRADIANCE_FRONT": np.concatenate(front).astype(np.float32),
            "_IRRADIANCE_BACK": np.concatenate(back).astype(np.float32),
            "indices": np.concatenate(index).astype(np.uint32)}


class _Builder:
    """Accumulates bufferViews and accessors over one binary buffer (4-byte aligned)."""

    def __init__(self):
        self.chunks, self.size, self.views, self.accessors = [], 0, [], []

    def add(self, array: np.ndarray, kind: str, target: int, bounds: bool = False) -> int:
        data = np.ascontiguousarray(array).tobytes()
        self.views.append({"buffer": 0, "byteOffset": self.size, "byteLength": len(data),
                           "target": target})
        self.chunks.append(data)
        self.size += len(data)
        pad = (-self.size) % 4
        if pad:
            self.chunks.append(b"\0" * pad)
            self.size += pad
        acc = {"bufferView": len(self.views) - 1, "componentType": FLOAT if array.dtype == np.float32 else UINT32,
               "count": int(array.shape[0] if kind != "SCALAR" else array.size), "type": kind}
        if bounds:
            acc["min"] = [float(x) for x in array.min(axis=0)]
            acc["max"] = [float(x) for x in array.max(axis=0)]
        self.accessors.append(acc)
        return len(self.accessors) - 1


def room_glb(lattice: dict, meshes: list[dict]) -> bytes:
    """The glb of a baked gallery. lattice: `Gallery._bake_lattice()`'s arrays. meshes: one
    dict per Embree geometry, in geometry order: {"name", "albedo", "emission"} and for a
    painting slot also {"slot", "painting", "origin", "u_axis", "v_axis", "width_m",
    "height_m"} (TEXCOORD_0 = u, v of each vertex on the painting, in [0, 1])."""
    b = _Builder()
    gl_meshes, materials, nodes = [], [], []
    geometry = lattice["geometry"]
    for g, info in enumerate(meshes):
        tris = np.flatnonzero(geometry == g)
        if len(tris) == 0:
            continue
        arrays = _mesh_arrays(lattice, tris)
        attrs = {"POSITION": b.add(arrays["POSITION"], "VEC3", ARRAY_BUFFER, bounds=True),
                 "_IRRADIANCE_FRONT": b.add(arrays["_IRRADIANCE_FRONT"], "VEC3", ARRAY_BUFFER),
                 "_IRRADIANCE_BACK": b.add(arrays["_IRRADIANCE_BACK"], "VEC3", ARRAY_BUFFER)}
        extras = {}
        if "slot" in info:
            rel = arrays["POSITION"].astype(np.float64) - np.asarray(info["origin"], np.float64)
            uv = np.stack([rel @ np.asarray(info["u_axis"], np.float64) / info["width_m"],
                           rel @ np.asarray(info["v_axis"], np.float64) / info["height_m"]], axis=1)
            attrs["TEXCOORD_0"] = b.add(np.clip(uv, 0, 1).astype(np.float32), "VEC2", ARRAY_BUFFER)
            extras = {"painting": int(info["painting"]), "slot": int(info["slot"])}
        indices = b.add(arrays["indices"].ravel(), "SCALAR", ELEMENT_ARRAY_BUFFER)
        materials.append({"name": info["name"], "doubleSided": True,
                          "pbrMetallicRoughness": {
                              "baseColorFactor": [float(x) for x in info["albedo"]] + [1.0],
                              "metallicFactor": 0.0, "roughnessFactor": 1.0},
                          "extras": {"emission": [float(x) for x in info["emission"]]}})
        mesh = {"name": info["name"], "primitives": [{"attributes": attrs, "indices": indices,
                                                      "material": len(materials) - 1, "mode": 4}]}
        if extras:
            mesh["extras"] = extras
        gl_meshes.append(mesh)
        nodes.append({"name": info["name"], "mesh": len(gl_meshes) - 1})
    doc = {"asset": {"version": "2.0", "generator": "gigascroll serve"},
           "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes,
           "meshes": gl_meshes, "materials": materials, "accessors": b.accessors,
           "bufferViews": b.views, "buffers": [{"byteLength": b.size}]}
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * ((-len(text)) % 4)
    total = 12 + 8 + len(text) + 8 + b.size
    return b"".join([struct.pack("<III", GLB_MAGIC, 2, total), struct.pack("<II", len(text), JSON_CHUNK),
                     text, struct.pack("<II", b.size, BIN_CHUNK), *b.chunks])


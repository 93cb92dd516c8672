"""The served room's glb against the core: read back by trimesh (a peer glTF reader), its
per-vertex irradiance interpolated at the points the core's display pass hits equals the
irradiance the core used there (`Gallery.render_display(..., hits=True)`), on the side facing
the eye; its materials are the room's; painting meshes carry the painting's uv. And the bake
cache: a second start reads the file instead of baking, and a changed pack gets a new key."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from gigascroll import build_pack, runtime
from gigascroll.experiments import pattern_image
from gigascroll.serve import baked_room, pack_hash
from gigascroll.serve.room_glb import lattice_template


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    root = tmp_path_factory.mktemp("glb")
    pack = build_pack(pattern_image(2000, 300), root / "p.pack")
    r = baked_room("scroll", pack, pack_hash(pack), cache_dir=root / "cache")
    assert not r.cache_hit and r.gallery.baked
    return pack, r


def load(path):
    scene = trimesh.load(path, process=False, force="scene")
    meshes = []
    for name, g in scene.geometry.items():
        meshes.append({"name": name, "v": np.asarray(g.vertices, np.float64),
                       "f": np.asarray(g.faces, np.int64),
                       "front": np.asarray(g.vertex_attributes["_IRRADIANCE_FRONT"], np.float64),
                       "back": np.asarray(g.vertex_attributes["_IRRADIANCE_BACK"], np.float64),
                       # trimesh flips glTF's v (top-down) to OpenGL's (bottom-up): undone
                       "uv": (np.asarray(g.visual.uv, np.float64) * [1, -1] + [0, 1]
                              if "painting" in g.metadata else None),
                       "meta": g.metadata, "material": g.visual.material})
    return meshes


def test_lattice_template_is_the_cores_order_and_cells():
    for n in (1, 2, 5):
        i, j, tris = lattice_template(n)
        assert len(i) == (n + 1) * (n + 2) // 2 and len(tris) == n * n
        # lattice_index(i, j, n) = i (n + 1) - i (i - 1) / 2 + j enumerates the points in order
        assert np.array_equal(i * (n + 1) - i * (i - 1) // 2 + j, np.arange(len(i)))
        # the sub-triangles tile the triangle: their areas (in (i, j) units) sum to n^2 / 2,
        # and each is wound as the triangle itself (positive area)
        p = np.stack([i, j], 1)[tris].astype(float)
        d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        area = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / 2
        assert np.allclose(area, 0.5) and area.sum() == n * n / 2


def _interpolate(meshes, p, eye):
    """The glb's irradiance at point p seen from eye (and the painting uv), for every
    sub-triangle p lies in (a list: points on a shared edge lie in several)."""
    found = []
    for m in meshes:
        lo, hi = m["lo"], m["hi"]
        cand = np.flatnonzero(np.all((lo <= p + 1e-4) & (hi >= p - 1e-4), axis=1))
        for t in cand:
            a, b, c = m["v"][m["f"][t]]
            n = np.cross(b - a, c - a)
            nn = np.linalg.norm(n)
            if abs(np.dot(n, p - a)) / nn > 1e-4:
                continue
            d00, d01, d11 = np.dot(b - a, b - a), np.dot(b - a, c - a), np.dot(c - a, c - a)
            d20, d21 = np.dot(p - a, b - a), np.dot(p - a, c - a)
            den = d00 * d11 - d01 * d01
            w1, w2 = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
            w = np.array([1 - w1 - w2, w1, w2])
            if w.min() < -1e-4:
                continue
            side = m["front"] if np.dot(n, eye - p) > 0 else m["back"]
            uv = w @ m["uv"][m["f"][t]] if m["uv"] is not None else None
            found.append((w @ side[m["f"][t]], uv))
    return found


@pytest.mark.parametrize("pose", [None, ((3.0, 2.2, -3.5), (0.5, 1.0, 0.0)),
                                  ((6.0, 0.6, -0.8), (2.0, 2.9, -4.0))])
def test_glb_irradiance_is_the_cores(room, pose, rng):
    pack, r = room
    meshes = load(r.glb_path)
    for m in meshes:
        corners = m["v"][m["f"]]
        m["lo"], m["hi"] = corners.min(axis=1), corners.max(axis=1)
    g = r.gallery
    eye, target = pose if pose else (None, None)
    camera = g.camera((96, 64), eye=eye, target=target)
    _, hits = g.render_display(camera, runtime.VirtualTexture(pack, (30, 30)), "baked", hits=True)
    pos, E = hits["position"].reshape(-1, 3), hits["irradiance"].reshape(-1, 3)
    slot, uv = hits["slot"].ravel(), hits["uv"].reshape(-1, 2)
    seen = np.flatnonzero(np.isfinite(pos[:, 0]))
    eye = np.array(camera.position)
    compared = ambiguous = painting_points = 0
    for k in rng.choice(seen, min(100, len(seen)), replace=False):
        found = _interpolate(meshes, pos[k].astype(np.float64), eye)
        assert found, f"pixel {k}: the core's hit {pos[k]} lies on no glb triangle"
        tol = 1e-3 * max(1.0, float(np.abs(E[k]).max()))
        close = [np.abs(e - E[k]).max() <= tol for e, _ in found]
        assert any(close), (pos[k], E[k], [e for e, _ in found])
        if all(close):
            compared += 1
        else:  # on an edge between two room triangles, whose lattices differ there
            ambiguous += 1
        if slot[k] >= 0:
            painting_points += 1
            assert any(u is not None and np.abs(u - uv[k]).max() < 1e-4 for _, u in found)
    assert compared >= 90 and ambiguous <= 10
    if pose is None:
        assert painting_points > 20  # the default view looks at the scroll


def test_glb_materials_and_extras_are_the_rooms(room):
    pack, r = room
    meshes = {m["name"]: m for m in load(r.glb_path)}
    for s in r.spec.surfaces:
        m = meshes[s.name]
        assert np.allclose(m["material"].baseColorFactor[:3] / 255.0, s.albedo, atol=1 / 255)
    paintings = [m for m in meshes.values() if "painting" in m["meta"]]
    assert len(paintings) == 1 and paintings[0]["meta"]["slot"] == 0
    assert paintings[0]["uv"].min() >= 0 and paintings[0]["uv"].max() <= 1
    # every lattice point is a vertex once: the bake's point count
    assert sum(len(m["v"]) for m in meshes.values()) == r.gallery.stats["bake_points"]
    # the emission is in extras, at full range (the spot lights are far above 1)
    import json
    from gigascroll.serve.room_glb import GLB_MAGIC  # noqa: F401  (the module writes glTF 2)
    data = r.glb_path.read_bytes()
    doc = json.loads(data[20:20 + int.from_bytes(data[12:16], "little")])
    emission = {mat["name"]: mat["extras"]["emission"] for mat in doc["materials"]}
    for s in r.spec.surfaces:
        assert np.allclose(emission[s.name], s.emission, rtol=1e-6)
    assert max(max(e) for e in emission.values()) > 1


def test_the_bake_is_cached_and_keyed(room, tmp_path, monkeypatch):
    pack, r = room
    cache = r.glb_path.parent
    again = baked_room("scroll", pack, pack_hash(pack), cache_dir=cache)
    assert again.cache_hit and again.key == r.key and not again.gallery.lit  # no light, no bake
    assert sorted(p.name for p in cache.iterdir()) == [r.glb_path.name]
    from gigascroll.serve import room_bake
    monkeypatch.setitem(room_bake.ROOM_LIGHTING, "photons", 1 << 10)   # other light: a new key
    assert room_bake.room_key(r.spec, pack_hash(pack), room_bake.lighting_options()) != r.key
    monkeypatch.undo()
    other = build_pack(pattern_image(2000, 300)[:, ::-1].copy(), tmp_path / "q.pack")
    moved = baked_room("scroll", other, pack_hash(other), cache_dir=cache)
    assert not moved.cache_hit and moved.key != r.key

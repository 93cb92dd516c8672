// Lines along the open edges of a room mesh, drawn after its triangles to fill the pixels that
// no triangle covers where surfaces meet.
//
// Each room triangle's bake lattice has its own number of segments, so where two triangles
// (or two surfaces: a wall and the floor) meet, their sub-triangles' vertices along the shared
// edge differ: T-junctions, whose rasteriser cracks let the clear colour through as isolated
// pixels. The core casts rays and has no such holes. An edge that only one sub-triangle of a
// mesh uses is such a seam (or the mesh's rim); a GL line along it covers the crack's pixels
// with the owning surface's light (its irradiance side picked by the owning triangle's normal,
// since lines have no facing), and the depth test keeps it behind the triangles it borders.

// {positions, irradianceFront, irradianceBack, normals, vertexCount} of the mesh's open edges
// as a line list, or null when the mesh has none.
export function openEdges(mesh) {
  const idx = mesh.indices ?? Uint32Array.from({ length: mesh.vertexCount }, (_, i) => i);
  const n = mesh.vertexCount, triangles = idx.length / 3;
  const keys = new Float64Array(idx.length);
  for (let t = 0; t < triangles; t++)
    for (let e = 0; e < 3; e++) {
      const a = idx[3 * t + e], b = idx[3 * t + ((e + 1) % 3)];
      keys[3 * t + e] = a < b ? a * n + b : b * n + a;
    }
  const sorted = keys.slice().sort();
  const single = [];
  for (let i = 0; i < sorted.length; i++)
    if (sorted[i] !== sorted[i - 1] && sorted[i] !== sorted[i + 1]) single.push(sorted[i]);
  if (!single.length) return null;
  const open = new Set(single);
  const p = mesh.positions, out = { positions: [], irradianceFront: [], irradianceBack: [], normals: [] };
  for (let t = 0; t < triangles; t++) {
    const v = [idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]];
    const normal = triangleNormal(p, v);
    for (let e = 0; e < 3; e++) {
      if (!open.has(keys[3 * t + e])) continue;
      for (const k of [v[e], v[(e + 1) % 3]]) {
        out.positions.push(p[3 * k], p[3 * k + 1], p[3 * k + 2]);
        for (const c of [0, 1, 2]) {
          out.irradianceFront.push(mesh.irradianceFront[3 * k + c]);
          out.irradianceBack.push(mesh.irradianceBack[3 * k + c]);
        }
        out.normals.push(...normal);
      }
    }
  }
  return {
    positions: new Float32Array(out.positions), irradianceFront: new Float32Array(out.irradianceFront),
    irradianceBack: new Float32Array(out.irradianceBack), normals: new Float32Array(out.normals),
    vertexCount: out.positions.length / 3,
  };
}

// The counter-clockwise normal (v1 - v0) x (v2 - v0) of a triangle: the glb's "front" side.
function triangleNormal(p, [a, b, c]) {
  const e1 = [p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1], p[3 * b + 2] - p[3 * a + 2]];
  const e2 = [p[3 * c] - p[3 * a], p[3 * c + 1] - p[3 * a + 1], p[3 * c + 2] - p[3 * a + 2]];
  return [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
}

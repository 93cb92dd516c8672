// A glTF 2.0 binary reader for the room `gigascroll serve` bakes (docs/serve-protocol.md):
// one mesh per room surface or painting slot, in room coordinates, with POSITION,
// _IRRADIANCE_FRONT, _IRRADIANCE_BACK (float32 VEC3), TEXCOORD_0 on paintings (float32 VEC2),
// optional indices, the material's baseColorFactor (albedo) and extras.emission, and
// extras.painting / extras.slot on painting meshes. Only what the room uses is read; anything
// else in the file (nodes, other attributes) is ignored. Malformed input throws an Error with
// a one-line message; arrays are views into the file's buffer (no copies).

const MAGIC = 0x46546c67, JSON_CHUNK = 0x4e4f534a, BIN_CHUNK = 0x004e4942;
const COMPONENTS = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };
const TYPED = { 5126: Float32Array, 5125: Uint32Array, 5123: Uint16Array, 5121: Uint8Array };

function fail(message) {
  throw new Error(`room glb: ${message}`);
}

// {json, bin}: the two chunks of a GLB container.
export function readChunks(arrayBuffer) {
  const dv = new DataView(arrayBuffer);
  if (arrayBuffer.byteLength < 20 || dv.getUint32(0, true) !== MAGIC) fail('not a glTF binary (bad magic)');
  if (dv.getUint32(4, true) !== 2) fail(`glTF version ${dv.getUint32(4, true)} is not 2`);
  if (dv.getUint32(8, true) > arrayBuffer.byteLength) fail('truncated file');
  let offset = 12, json = null, bin = null;
  while (offset + 8 <= arrayBuffer.byteLength) {
    const length = dv.getUint32(offset, true), type = dv.getUint32(offset + 4, true);
    const start = offset + 8;
    if (start + length > arrayBuffer.byteLength) fail('a chunk runs past the end of the file');
    if (type === JSON_CHUNK && json === null) {
      try {
        json = JSON.parse(new TextDecoder().decode(new Uint8Array(arrayBuffer, start, length)));
      } catch {
        fail('the JSON chunk is not JSON');
      }
    }
    else if (type === BIN_CHUNK && bin === null) bin = { offset: start, length };
    offset = start + ((length + 3) & ~3);
  }
  if (json === null) fail('no JSON chunk');
  return { json, bin };
}

// The typed array of accessor `index` (a view into the buffer; copied only when unaligned).
function accessorArray(gltf, arrayBuffer, bin, index, wantType, wantComponents) {
  const acc = gltf.accessors?.[index];
  if (!acc) fail(`accessor ${index} missing`);
  const Typed = TYPED[acc.componentType];
  if (!Typed || (wantType && Typed !== wantType)) fail(`accessor ${index}: component type ${acc.componentType} unexpected`);
  const n = COMPONENTS[acc.type];
  if (!n || (wantComponents && n !== wantComponents)) fail(`accessor ${index}: type ${acc.type} unexpected`);
  const view = gltf.bufferViews?.[acc.bufferView];
  if (!view || !bin || (view.buffer ?? 0) !== 0) fail(`accessor ${index}: no buffer view in the binary chunk`);
  if (view.byteStride && view.byteStride !== n * Typed.BYTES_PER_ELEMENT) fail(`accessor ${index}: interleaved data is not supported`);
  const count = acc.count, start = (view.byteOffset ?? 0) + (acc.byteOffset ?? 0);
  const bytes = count * n * Typed.BYTES_PER_ELEMENT;
  if (!(Number.isInteger(count) && count >= 0) || start + bytes > (view.byteOffset ?? 0) + view.byteLength || view.byteOffset + view.byteLength > bin.length)
    fail(`accessor ${index} runs past its buffer`);
  const at = bin.offset + start;
  if (at % Typed.BYTES_PER_ELEMENT === 0) return new Typed(arrayBuffer, at, count * n);
  return new Typed(arrayBuffer.slice(at, at + bytes));
}

function vec3Of(value, fallback, what) {
  if (value === undefined) return fallback;
  if (!Array.isArray(value) || value.length < 3 || !value.slice(0, 3).every(Number.isFinite)) fail(`${what} is not 3 numbers`);
  return value.slice(0, 3);
}

// One drawable primitive per mesh primitive:
// {name, positions, irradianceFront, irradianceBack, texcoords|null, indices|null, vertexCount,
//  albedo [r,g,b], emission [r,g,b], painting (index or -1), slot (or -1)}.
export function parseRoom(arrayBuffer) {
  const { json: gltf, bin } = readChunks(arrayBuffer);
  if (!gltf.asset || String(gltf.asset.version) !== '2.0') fail('asset.version is not 2.0');
  const out = [];
  for (const [meshIndex, mesh] of (gltf.meshes ?? []).entries()) {
    for (const prim of mesh.primitives ?? []) {
      if ((prim.mode ?? 4) !== 4) fail(`mesh ${meshIndex}: only triangle lists are supported`);
      const a = prim.attributes ?? {};
      for (const name of ['POSITION', '_IRRADIANCE_FRONT', '_IRRADIANCE_BACK'])
        if (a[name] === undefined) fail(`mesh ${meshIndex} has no ${name}`);
      const get = (i, T, n) => accessorArray(gltf, arrayBuffer, bin, i, T, n);
      const positions = get(a.POSITION, Float32Array, 3);
      const vertexCount = positions.length / 3;
      const irradianceFront = get(a._IRRADIANCE_FRONT, Float32Array, 3);
      const irradianceBack = get(a._IRRADIANCE_BACK, Float32Array, 3);
      const texcoords = a.TEXCOORD_0 === undefined ? null : get(a.TEXCOORD_0, Float32Array, 2);
      for (const [what, arr, k] of [['irradiance', irradianceFront, 3], ['irradiance', irradianceBack, 3], ['TEXCOORD_0', texcoords, 2]])
        if (arr && arr.length !== vertexCount * k) fail(`mesh ${meshIndex}: ${what} count differs from POSITION`);
      const indices = prim.indices === undefined ? null : get(prim.indices, null, 1);
      if (indices && indices.length % 3) fail(`mesh ${meshIndex}: index count is not a multiple of 3`);
      if (indices) for (const i of indices) if (i >= vertexCount) fail(`mesh ${meshIndex}: an index is out of range`);
      if (!indices && vertexCount % 3) fail(`mesh ${meshIndex}: vertex count is not a multiple of 3`);
      const material = prim.material === undefined ? {} : gltf.materials?.[prim.material];
      if (!material) fail(`mesh ${meshIndex}: material ${prim.material} missing`);
      const extras = { ...(mesh.extras ?? {}), ...(prim.extras ?? {}) };
      const painting = Number.isInteger(extras.painting) ? extras.painting : -1;
      if (painting >= 0 && !texcoords) fail(`mesh ${meshIndex}: a painting without TEXCOORD_0`);
      out.push({
        name: mesh.name ?? `mesh${meshIndex}`, positions, irradianceFront, irradianceBack, texcoords, indices, vertexCount,
        albedo: vec3Of(material.pbrMetallicRoughness?.baseColorFactor, [1, 1, 1], `mesh ${meshIndex}: baseColorFactor`),
        emission: vec3Of(material.extras?.emission, [0, 0, 0], `mesh ${meshIndex}: extras.emission`),
        painting, slot: Number.isInteger(extras.slot) ? extras.slot : -1,
      });
    }
  }
  if (!out.length) fail('no meshes');
  return out;
}

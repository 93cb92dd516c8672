// GLSL ES 3.00 of the display pass: the room's light as the core's baked display computes it.
//
//   radiance = albedo * E / pi + emission
//
// E is the baked irradiance interpolated across the bake lattice's sub-triangle (the glb's
// vertices are its lattice points, so the rasteriser's barycentric interpolation is the core's
// lattice_lerp), on the side of the surface facing the eye: the glb's "front" is the side its
// triangles' counter-clockwise normal faces, which is the side gl_FrontFacing reports. A
// painting's albedo is the core's painting_albedo: 0.9 x the linearised sRGB texel of the
// virtual texture's trilinear sample (python/gigascroll/gallery/gallery.py). The result goes
// through the display mapping scene.json names (DISPLAY_MAPPINGS below), never one of our own.

export const PAINTING_REFLECTANCE = 0.9;

export const HEADER = `#version 300 es
precision highp float;
precision highp int;
`;

// Attribute locations shared by every program drawing the room's meshes.
export const ATTRIBUTES = { position: 0, irradianceFront: 1, irradianceBack: 2, texcoord: 3, normal: 4 };

export const ROOM_VS = `
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aIrradianceFront;
layout(location = 2) in vec3 aIrradianceBack;
layout(location = 3) in vec2 aTexcoord;
layout(location = 4) in vec3 aNormal;   // crack-fill lines only (crack_fill.js)
uniform mat4 uViewProj;
uniform bool uLines;
uniform vec3 uEye;
// Crack-fill lines slide 1% farther along their eye ray (the same pixels): a crack shows what
// lies beyond the room (nothing), so they still fill it, while at a surface's silhouette over
// another one close behind (a light panel 2 cm under the ceiling) they stay hidden.
const float LINE_PUSH = 0.01;
out vec3 vIrradianceFront;
out vec3 vIrradianceBack;
out vec2 vUv;
out vec3 vWorld;
out vec3 vNormal;
void main() {
  vIrradianceFront = aIrradianceFront;
  vIrradianceBack = aIrradianceBack;
  vUv = aTexcoord;
  vWorld = aPosition;
  vNormal = aNormal;
  vec3 p = uLines ? aPosition + LINE_PUSH * (aPosition - uEye) : aPosition;
  gl_Position = uViewProj * vec4(p, 1.0);
}
`;

// The display mappings of scene.json's display.tone, each `vec3 displayMap(vec3 radiance)`
// with uniform uExposure: the GLSL twins of python/gigascroll/display_mapping.py (to_display,
// then srgb_encode), the one camera response of every image; tests/python/
// test_display_mapping_browser.py draws a ramp through both. "neutral-srgb" is the Khronos PBR
// Neutral tone mapper (KhronosGroup/ToneMapping, PBR_Neutral: the reference's constants) of the
// exposed radiance; "clip-srgb" clamps it to [0, 1]. The 8-bit target rounds to nearest as the
// CPU's (s * 255 + 0.5) does.
const SRGB_ENCODE = `
vec3 srgbEncode(vec3 c) {
  return mix(1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, 12.92 * c, vec3(lessThanEqual(c, vec3(0.0031308))));
}
`;

export const DISPLAY_MAPPINGS = {
  'neutral-srgb': `${SRGB_ENCODE}
uniform float uExposure;
// display_mapping.pbr_neutral: identity less an offset up to startCompression, then the peak
// channel compressed towards 1 and desaturated in the plane of the colour and white (no hue shift).
vec3 pbrNeutral(vec3 color) {
  const float startCompression = 0.8 - 0.04;
  const float desaturation = 0.15;
  float x = min(color.r, min(color.g, color.b));
  float offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
  color -= offset;
  float peak = max(color.r, max(color.g, color.b));
  if (peak < startCompression) return color;
  const float d = 1.0 - startCompression;
  float newPeak = 1.0 - d * d / (peak + d - startCompression);
  color *= newPeak / peak;
  float g = 1.0 - 1.0 / (desaturation * (peak - newPeak) + 1.0);
  return mix(color, newPeak * vec3(1.0), g);
}
vec3 displayMap(vec3 radiance) {
  return srgbEncode(min(pbrNeutral(max(uExposure * radiance, 0.0)), 1.0));
}
`,
  'clip-srgb': `${SRGB_ENCODE}
uniform float uExposure;
vec3 displayMap(vec3 radiance) {
  return srgbEncode(clamp(uExposure * radiance, 0.0, 1.0));
}
`,
};

export function displayMapping(display) {
  const glsl = DISPLAY_MAPPINGS[display?.tone];
  if (!glsl) throw new Error(`scene.json: display tone ${JSON.stringify(display?.tone)} is not one this client knows (${Object.keys(DISPLAY_MAPPINGS).join(', ')})`);
  if (!(Number.isFinite(display.exposure) && display.exposure > 0)) throw new Error(`scene.json: display exposure ${display.exposure} is not a positive number`);
  return glsl;
}

const LIGHT = `
uniform vec3 uEmission;
in vec3 vIrradianceFront;
in vec3 vIrradianceBack;
in vec2 vUv;
in vec3 vWorld;
in vec3 vNormal;
uniform bool uLines;   // lines have no facing: their owning triangle's normal decides
uniform vec3 uEye;
out vec4 fragColor;
const float PI = 3.14159265358979;
vec3 irradiance() {
  bool front = uLines ? dot(vNormal, uEye - vWorld) > 0.0 : gl_FrontFacing;
  return front ? vIrradianceFront : vIrradianceBack;
}
vec3 srgbToLinear(vec3 s) {
  return mix(pow((s + 0.055) / 1.055, vec3(2.4)), s / 12.92, vec3(lessThanEqual(s, vec3(0.04045))));
}
`;

// Room surfaces: a constant albedo per mesh.
export const ROOM_FS = `${LIGHT}
uniform vec3 uAlbedo;
void main() {
  fragColor = vec4(displayMap(uAlbedo * irradiance() / PI + uEmission), 1.0);
}
`;

// Paintings: the albedo from the virtual texture (vtSample / vtLod come from vt.glsl).
export const PAINTING_FS = `${LIGHT}
uniform int uPainting;
void main() {
  vec3 texel = vtSample(uPainting, vUv, vtLod(uPainting, vUv)).rgb;
  vec3 albedo = ${PAINTING_REFLECTANCE.toFixed(1)} * srgbToLinear(texel);
  fragColor = vec4(displayMap(albedo * irradiance() / PI + uEmission), 1.0);
}
`;

// The inset's blit: a texture onto a rectangle of the view ([x0, y0, x1, y1] in NDC).
export const BLIT_VS = `
uniform vec4 uRect;
out vec2 vUv;
void main() {
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  vUv = corner;
  gl_Position = vec4(mix(uRect.xy, uRect.zw, corner), 0.0, 1.0);
}
`;

export const BLIT_FS = `
uniform sampler2D uImage;
uniform float uRim;
in vec2 vUv;
out vec4 fragColor;
void main() {
  vec2 d = abs(vUv - 0.5);
  bool rim = max(d.x, d.y) > 0.5 - uRim;
  fragColor = rim ? vec4(0.08, 0.08, 0.08, 1.0) : vec4(texture(uImage, vUv).rgb, 1.0);
}
`;

// GLSL ES 3.00 for sampling the virtual texture and writing feedback, the core's arithmetic
// (sampling/sampler.cpp's per-sample trilinear path, sampling/bilinear.h, views/feedback.cpp):
//
//   tap on an axis of n texels at level l: x = clamp(x0 2^-l, 0.5, n - 0.5), t = x - 0.5,
//     i = floor(t), f = t - i (clamp to edge);
//   the tile holding the nearest texel: c = floor((i + (f >= 0.5)) / P);
//   its page entry (level al >= l, slot): the finest resident tile covering it (eqs 5, 6);
//   if al > l the taps are redone at al (the fallback answers at its own resolution);
//   texel in the slot (eqs 7-10): j = clamp(i - (c >> (al - l)) P + E, 0, T - 2), so the
//     2 x 2 footprint stays inside the tile and its border;
//   bilinear with weights (1-f)(1-g), f(1-g), (1-f)g, fg, by texelFetch in float (not the
//     hardware filter, whose weights have 8 bits of fraction on many GPUs; with
//     VT_HARDWARE_BILINEAR defined, the option hardwareBilinear, one filtered fetch instead
//     of four, for GPUs short of texture rate: 0.02 of a code from the core's on SwiftShader,
//     up to about half a code with 8-bit weight fractions);
//   trilinear: l0 = floor(lod) (lod clamped to [0, levels - 1]), blended with l0 + 1 by
//     lod - l0.
//
// Where the GPU's rounding differs from the core's: positions are float32 here, double
// there. u W rounds to float32 (about 0.01 texel at u near 1 on a 152089-texel scroll, 6e-5
// on a 1000-texel painting), which moves the weights by as much and, for a position within
// that distance of a texel centre at a tile's edge, may pick the neighbouring tile (whose
// border holds the same texels when both are resident at that level). The sums run in
// float32 in both, in the core over 0..255 codes, here over codes / 255: within 1e-4 of a
// code.
//
// The level of detail is the core's feedback rule: rho = the larger of |d(u W, v H)/dx| and
// |d(u W, v H)/dy| per display pixel (the OpenGL specification's), lambda = log2(rho); the
// feedback level is floor(lambda) clamped to [0, levels - 1], taken from rho^2's exponent
// exactly as plane_keys does. The derivatives are the GPU's finite differences over a 2 x 2
// pixel quad instead of the core's analytic ray differentials: pixels where lambda lies
// within their difference of an integer can pick the other level.

export const samplerGlsl = /* glsl */ `
uniform highp usampler2D uVtTable;     // merged page table, mip level l = table level l
uniform highp usampler2D uVtTail;      // every painting's tail levels
uniform highp usampler2D uVtInfo;      // (l, p): grid origin, tail?, first tile index
uniform highp sampler2D uVtPhysical;   // RGB8 tile slots
uniform highp ivec4 uVtTile;           // tile size T, border E, payload P, slots_x
uniform highp vec2 uVtPixelScale;      // display pixels per target pixel, inverted per axis

const highp uint VT_NONE = 0xFFFFFFFFu;

// (width, height, levels) of painting p.
highp ivec3 vtPainting(int p) {
  return ivec3(texelFetch(uVtInfo, ivec2(32, p), 0).xyz);
}

// Page entry (level << 24 | slot) of tile (cx, cy) at level l of painting p.
highp uint vtEntry(int p, int l, int cx, int cy) {
  highp uvec4 o = texelFetch(uVtInfo, ivec2(l, p), 0);
  highp ivec2 at = ivec2(o.xy) + ivec2(cx, cy);
  return o.z == 0u ? texelFetch(uVtTable, at, l).r : texelFetch(uVtTail, at, 0).r;
}

// 2^-l exactly (from the exponent's bits, as the core's bilinear_taps).
highp float vtScale(int l) { return intBitsToFloat((127 - l) << 23); }

// Level l's extent of an axis of n level-0 texels: ceil(n / 2^l).
int vtExtent(int n, int l) { return (n + (1 << l) - 1) >> l; }

// bilinear_tap: texel i and weight f of the second texel on an axis of n texels.
void vtTap(highp float x0, int l, int n, out int i, out highp float f) {
  highp float x = clamp(x0 * vtScale(l), 0.5, float(n) - 0.5);
  highp float t = x - 0.5;
  i = int(t);
  f = t - float(i);
}

// Bilinear at level l with the page table's fallback (sample_trilinear_serial's bilinear).
highp vec3 vtBilinear(int p, highp vec2 x0, int l, ivec2 size) {
  int T = uVtTile.x, E = uVtTile.y, P = uVtTile.z;
  int i, j;
  highp float f, g;
  vtTap(x0.x, l, vtExtent(size.x, l), i, f);
  vtTap(x0.y, l, vtExtent(size.y, l), j, g);
  int cx = (i + (f >= 0.5 ? 1 : 0)) / P, cy = (j + (g >= 0.5 ? 1 : 0)) / P;
  highp uint e = vtEntry(p, l, cx, cy);
  if (e == VT_NONE) return vec3(0.0);  // only before the pinned tiles arrive
  int al = int(e >> 24u), slot = int(e & 0xFFFFFFu), s = al - l;
  if (s != 0) {
    vtTap(x0.x, al, vtExtent(size.x, al), i, f);
    vtTap(x0.y, al, vtExtent(size.y, al), j, g);
  }
  int jx = clamp(i - (cx >> s) * P + E, 0, T - 2), jy = clamp(j - (cy >> s) * P + E, 0, T - 2);
  ivec2 at = ivec2(slot % uVtTile.w, slot / uVtTile.w) * T + ivec2(jx, jy);
#ifdef VT_HARDWARE_BILINEAR
  // One filtered fetch at the footprint's position: 1 texture read instead of 4, weights
  // rounded by the hardware (8 bits of fraction on many GPUs).
  return textureLod(uVtPhysical, (vec2(at) + vec2(f, g) + 0.5) / vec2(textureSize(uVtPhysical, 0)), 0.0).rgb;
#else
  highp vec3 t00 = texelFetch(uVtPhysical, at, 0).rgb;
  highp vec3 t10 = texelFetch(uVtPhysical, at + ivec2(1, 0), 0).rgb;
  highp vec3 t01 = texelFetch(uVtPhysical, at + ivec2(0, 1), 0).rgb;
  highp vec3 t11 = texelFetch(uVtPhysical, at + ivec2(1, 1), 0).rgb;
  highp float w00 = (1.0 - f) * (1.0 - g), w10 = f * (1.0 - g), w01 = (1.0 - f) * g, w11 = f * g;
  return w00 * t00 + w10 * t10 + w01 * t01 + w11 * t11;
#endif
}

// The painting's sRGB8 colour as 0..1 at uv (clamped to [0, 1]), trilinear at lod.
highp vec4 vtSample(int p, highp vec2 uv, highp float lod) {
  highp ivec3 info = vtPainting(p);
  highp vec2 x0 = clamp(uv, 0.0, 1.0) * vec2(info.xy);
  highp float top = float(info.z - 1);
  highp float lc = lod > 0.0 ? min(lod, top) : 0.0;  // NaN reads level 0, as the core
  int l0 = int(lc);
  highp float t = lc - float(l0);
  highp vec3 c = vtBilinear(p, x0, l0, info.xy);
  if (t > 0.0 && l0 + 1 < info.z) c += t * (vtBilinear(p, x0, l0 + 1, info.xy) - c);
  return vec4(c, 1.0);
}

// rho^2: the squared footprint of a display pixel in level-0 texels.
highp float vtRho2(int p, highp vec2 uv) {
  highp vec2 size = vec2(vtPainting(p).xy);
  highp vec2 dx = dFdx(uv) * size * uVtPixelScale.x, dy = dFdy(uv) * size * uVtPixelScale.y;
  return max(dot(dx, dx), dot(dy, dy));
}

// lambda = log2(rho): the level of detail a display pixel samples at.
highp float vtLod(int p, highp vec2 uv) { return 0.5 * log2(vtRho2(p, uv)); }

// The feedback pass's output for painting p at uv: the flat index of the requested tile in
// 32 bits as RGBA8 (little-endian bytes). The level is floor(lambda) from rho^2's binary
// exponent, clamped; the tile holds texel min(floor(x) >> level, last) with x = u W clamped
// to [0, W] (PlaneFrame::tile_key).
highp vec4 vtFeedbackOut(int p, highp vec2 uv) {
  highp float r2 = vtRho2(p, uv);
  highp ivec3 info = vtPainting(p);
  int top = info.z - 1;
  int level = r2 > 1.0 ? min(((floatBitsToInt(r2) >> 23) - 127) >> 1, top) : 0;
  highp vec2 x = clamp(uv * vec2(info.xy), vec2(0.0), vec2(info.xy));
  int lastX = vtExtent(info.x, level) - 1, lastY = vtExtent(info.y, level) - 1;
  int P = uVtTile.z;
  int tx = min(int(x.x) >> level, lastX) / P, ty = min(int(x.y) >> level, lastY) / P;
  highp uint first = texelFetch(uVtInfo, ivec2(level, p), 0).w;
  highp uint index = first + uint(ty * (lastX / P + 1) + tx);
  return vec4(uvec4(index & 255u, (index >> 8u) & 255u, (index >> 16u) & 255u, index >> 24u)) / 255.0;
}

// What the feedback pass writes where no painting is seen (the room's surfaces).
highp vec4 vtFeedbackNone() { return vec4(1.0); }
`;

// The "shade" step of the display pass in lanes: a packet's radiance from its light and, on a
// painting, its texels; and the eye-facing normals' inverse square roots.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "common/vec3.h"
#include "display/display_options.h"
#include "display/lattice_lanes.h"
#include "display/srgb.h"

namespace gigascroll {
namespace display {

// 1 / sqrt(x) for x > 0 to about 1e-7 relative: the hardware estimate and one Newton step
// (a square root and a division per pixel were a tenth of the fused loop).
inline float inverse_sqrt(float x) {
#if defined(__SSE__)
    const float r = _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(x)));
    return r * (1.5f - 0.5f * x * r * r);
#else
    return 1.0f / std::sqrt(x);
#endif
}

// inverse_sqrt of 16 values in place, in SIMD lanes (the same estimate and Newton step).
inline void inverse_sqrt_16(float* x) {
#if defined(__AVX__)
    for (int k = 0; k < 16; k += 8) {
        const __m256 v = _mm256_load_ps(x + k), r = _mm256_rsqrt_ps(v);
        const __m256 half_v_r2 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), v), r), r);
        _mm256_store_ps(x + k, _mm256_mul_ps(r, _mm256_sub_ps(_mm256_set1_ps(1.5f), half_v_r2)));
    }
#else
    for (int k = 0; k < 16; ++k) x[k] = inverse_sqrt(x[k]);
#endif
}

#if defined(__AVX512F__)
// GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics (bug 105593), muted.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// 16 pixels' channels (R, G, B in lanes) stored interleaved at out[0..47] (the first n pixels'
// at out[0..3n-1]), with two two-source permutes per output vector: R and G into place, then B.
inline void store_rgb16(__m512 R, __m512 G, __m512 B, float* out, std::uint32_t n = 16) {
    struct Indices {
        alignas(64) std::int32_t rg[3][16], b[3][16];
        constexpr Indices() : rg{}, b{} {
            for (int o = 0; o < 3; ++o)
                for (int j = 0; j < 16; ++j) {
                    const int g = 16 * o + j, pixel = g / 3, channel = g % 3;
                    rg[o][j] = channel == 0 ? pixel : (channel == 1 ? 16 + pixel : 0);
                    b[o][j] = channel == 2 ? 16 + pixel : j;
                }
        }
    };
    static constexpr Indices kIdx;
    for (int o = 0; o < 3; ++o) {
        const __m512 rg = _mm512_permutex2var_ps(R, _mm512_load_si512(kIdx.rg[o]), G);
        const __m512 rgb = _mm512_permutex2var_ps(rg, _mm512_load_si512(kIdx.b[o]), B);
        if (n == 16) {
            _mm512_storeu_ps(out + 16 * o, rgb);
        } else {  // the first n pixels only: 3n floats
            const int floats = std::clamp(3 * int(n) - 16 * o, 0, 16);
            _mm512_mask_storeu_ps(out + 16 * o, __mmask16((1u << floats) - 1), rgb);
        }
    }
}

// A packet of 16 painting pixels shaded in lanes from their texels (channels apart, 0..255)
// and light into rgb (16 pixels x 3): the operations of the row's shading of its pending
// pixels in the same order (SrgbCurve's decode; albedo x reflectance; x irradiance / pi;
// + emission), so the same floats.
inline void shade_packet(const float (&tex)[3][16], const float (&E)[3][16], const float (&M)[3][16],
                  const DisplayOptions& o, const SrgbCurve& srgb, float* __restrict rgb, std::uint32_t n = 16) {
    const __m512 reflectance = _mm512_set1_ps(o.painting_reflectance);
    const __m512 inv_pi = _mm512_set1_ps(kInvPi);
    __m512 L[3];
    for (int c = 0; c < 3; ++c) {
        const __m512 code = _mm512_load_ps(tex[c]);
        const __m512 albedo = o.srgb_albedo
                                  ? _mm512_mul_ps(srgb.decode16(code), reflectance)
                                  : _mm512_mul_ps(_mm512_mul_ps(code, _mm512_set1_ps(1.0f / 255.0f)), reflectance);
        const __m512 scale = _mm512_mul_ps(_mm512_load_ps(E[c]), inv_pi);
        L[c] = _mm512_add_ps(_mm512_mul_ps(albedo, scale), _mm512_load_ps(M[c]));
    }
    store_rgb16(L[0], L[1], L[2], rgb, n);
}

// A packet of 16 pixels on a room surface shaded in lanes into rgb (the first n pixels):
// albedo x irradiance / pi + emission, the operations of the row's per-pixel loop in its
// order, so the same floats; their levels (lod) NaN, as every pixel off the paintings.
inline void shade_room_packet(const LaneLight& L, float* __restrict rgb, float* __restrict lod, std::uint32_t n = 16) {
    const __m512 inv_pi = _mm512_set1_ps(kInvPi);
    auto radiance = [&](int c) {
        return _mm512_add_ps(_mm512_mul_ps(_mm512_mul_ps(_mm512_load_ps(L.a[c]), _mm512_load_ps(L.E[c])), inv_pi),
                             _mm512_load_ps(L.M[c]));
    };
    store_rgb16(radiance(0), radiance(1), radiance(2), rgb, n);
    const __m512 nan = _mm512_set1_ps(std::numeric_limits<float>::quiet_NaN());
    if (n == 16)  // a whole packet (nearly all): a plain store, a masked one costs twice as much
        _mm512_storeu_ps(lod, nan);
    else
        _mm512_mask_storeu_ps(lod, __mmask16((1u << n) - 1), nan);
}
#pragma GCC diagnostic pop
#endif

}  // namespace display
}  // namespace gigascroll

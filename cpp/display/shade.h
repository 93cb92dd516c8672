// The "shade" step of the display pass in lanes: a packet's radiance from its light and, on a
// painting, its texels; and the eye-facing normals' inverse square roots. One text for every
// width (common/lanes.h); the packet's pixels interleaved into the image by store_rgb.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "common/lanes.h"
#include "common/vec3.h"
#include "display/display_options.h"
#include "display/lattice_lanes.h"
#include "display/srgb.h"

namespace gigascroll {
namespace display {

// 1 / sqrt(x) for x > 0 to about 1e-7 relative: the hardware estimate and one Newton step
// (a square root and a division per pixel were a tenth of the fused loop).
template <int W>
typename Lanes<W>::F inverse_sqrt(typename Lanes<W>::F x) {
    using F = typename Lanes<W>::F;
    const F r = rsqrt_estimate(x);
    return r * (F(1.5f) - F(0.5f) * x * r * r);
}
inline float inverse_sqrt(float x) { return inverse_sqrt<1>(Lanes<1>::F(x)).v; }

// inverse_sqrt of 16 values in place, W at a time.
template <int W = kWidest>
void inverse_sqrt_16(float* x) {
    for (int k = 0; k < 16; k += W) inverse_sqrt<W>(Lanes<W>::F::load(x + k)).store(x + k);
}

// W pixels' channels (R, G, B in lanes) stored interleaved at out[0..3W-1] (the first n
// pixels' at out[0..3n-1]), through the lanes' bits in memory.
template <int W>
[[gnu::always_inline]] inline void store_rgb(typename Lanes<W>::F R, typename Lanes<W>::F G, typename Lanes<W>::F B, float* out,
               std::uint32_t n) {
    alignas(64) float c[3][W];
    R.store(c[0]), G.store(c[1]), B.store(c[2]);
    for (std::uint32_t k = 0; k < n && k < std::uint32_t(W); ++k)
        out[3 * k] = c[0][k], out[3 * k + 1] = c[1][k], out[3 * k + 2] = c[2][k];
}
#if defined(__AVX512F__)
// GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics (bug 105593), muted.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// At 16 lanes, two two-source permutes per output vector: R and G into place, then B.
template <>
[[gnu::always_inline]] inline void store_rgb<16>(Lanes<16>::F R, Lanes<16>::F G, Lanes<16>::F B, float* out, std::uint32_t n) {
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
        const __m512 rg = _mm512_permutex2var_ps(R.v, _mm512_load_si512(kIdx.rg[o]), G.v);
        const __m512 rgb = _mm512_permutex2var_ps(rg, _mm512_load_si512(kIdx.b[o]), B.v);
        if (n >= 16) {
            _mm512_storeu_ps(out + 16 * o, rgb);
        } else {  // the first n pixels only: 3n floats
            const int floats = std::clamp(3 * int(n) - 16 * o, 0, 16);
            _mm512_mask_storeu_ps(out + 16 * o, __mmask16((1u << floats) - 1), rgb);
        }
    }
}
#pragma GCC diagnostic pop
#endif

// The pixels of a 16-pixel packet that lanes k0 .. k0 + W - 1 hold, of its first n.
inline std::uint32_t lanes_of(std::uint32_t n, int k0) { return n > std::uint32_t(k0) ? n - std::uint32_t(k0) : 0; }

// A packet of 16 painting pixels shaded in lanes from their texels (channels apart, 0..255)
// and light into rgb (16 pixels x 3; the first n): the operations of the row's shading of
// its pending pixels in the same order (SrgbCurve's decode; albedo x reflectance;
// x irradiance / pi; + emission), so the same floats.
template <int W = kWidest>
[[gnu::always_inline]] inline void shade_packet(const float (&tex)[3][16], const float (&E)[3][16], const float (&M)[3][16],
                  const DisplayOptions& o, const SrgbCurve& srgb, float* __restrict rgb, std::uint32_t n = 16) {
    using F = typename Lanes<W>::F;
    const F reflectance(o.painting_reflectance), inv_pi(kInvPi);
    for (int k = 0; k < 16 && lanes_of(n, k); k += W) {
        F L[3];
        for (int c = 0; c < 3; ++c) {
            const F code = F::load(tex[c] + k);
            const F albedo = o.srgb_albedo ? srgb.decode<W>(code) * reflectance
                                           : code * F(1.0f / 255.0f) * reflectance;
            const F scale = F::load(E[c] + k) * inv_pi;
            L[c] = albedo * scale + F::load(M[c] + k);
        }
        store_rgb<W>(L[0], L[1], L[2], rgb + 3 * k, lanes_of(n, k));
    }
}

// A packet of 16 pixels on a room surface shaded in lanes into rgb (the first n pixels):
// albedo x irradiance / pi + emission, the operations of the row's per-pixel loop in its
// order, so the same floats; their levels (lod) NaN, as every pixel off the paintings.
template <int W = kWidest>
[[gnu::always_inline]] inline void shade_room_packet(const LaneLight& L, float* __restrict rgb, float* __restrict lod, std::uint32_t n = 16) {
    using F = typename Lanes<W>::F;
    const F inv_pi(kInvPi), nan(std::numeric_limits<float>::quiet_NaN());
    for (int k = 0; k < 16 && lanes_of(n, k); k += W) {
        auto radiance = [&](int c) { return F::load(L.a[c] + k) * F::load(L.E[c] + k) * inv_pi + F::load(L.M[c] + k); };
        store_rgb<W>(radiance(0), radiance(1), radiance(2), rgb + 3 * k, lanes_of(n, k));
        store_first(nan, lod + k, lanes_of(n, k));
    }
}

}  // namespace display
}  // namespace gigascroll

// The filtering shared by virtual-texture sampling and the plain mip-mapped texture, so the
// two differ only by the indirection. The blends of one pixel's channels in SSE's four lanes
// (a lane type of W pixels cannot say them) each have a plain C++ twin that the tests compare
// with bit for bit (tests/cpp/sampling/test_bilinear.cpp). Coordinates are continuous texel positions (texel i
// covers [i, i + 1)), kept in double: at u near 1 on a 196301-texel painting a float would
// be off by ~0.01 texel, a double by ~1e-11.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#if defined(__AVX2__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace gigascroll {

// One axis of a bilinear footprint: texels i0 and i0 + 1, weight f of the second.
struct Tap {
    std::int64_t i0;
    float f;
};

// Clamp-to-edge on an axis of n texels: clamping the position to [0.5, n - 0.5] gives the
// same result as clamping texel indices, and keeps i0 + 1 inside [0, n] (weight 0 at n).
// t = x - 0.5 >= 0 after the clamp, so truncation is the floor (SSE2 has no floor
// instruction; this is the sampler's innermost arithmetic).
inline Tap bilinear_tap(double x, std::uint32_t n) {
    x = std::clamp(x, 0.5, double(n) - 0.5);
    const double t = x - 0.5;
    const auto i = static_cast<std::int64_t>(t);
    return {i, static_cast<float>(t - static_cast<double>(i))};
}

// Per-level sizes and scales of one painting, so a tap costs a multiply instead of ldexp and
// a ceil-division. Level l is ceil(W / 2^l) x ceil(H / 2^l) texels; x_l = x0 * 2^-l exactly.
class LevelAxes {
public:
    static constexpr std::uint32_t kMaxLevels = 32;
    LevelAxes(std::uint32_t width, std::uint32_t height, std::uint32_t levels) {
        for (std::uint32_t l = 0; l < levels && l < kMaxLevels; ++l) {
            scale_[l] = 1.0 / double(std::uint64_t(1) << l);
            w_[l] = (width + (1u << l) - 1) >> l;
            h_[l] = (height + (1u << l) - 1) >> l;
        }
    }
    Tap tap_x(double x0, std::uint32_t l) const { return bilinear_tap(x0 * scale_[l], w_[l]); }
    Tap tap_y(double y0, std::uint32_t l) const { return bilinear_tap(y0 * scale_[l], h_[l]); }
    std::uint32_t width(std::uint32_t l) const { return w_[l]; }
    std::uint32_t height(std::uint32_t l) const { return h_[l]; }

private:
    double scale_[kMaxLevels] = {};
    std::uint32_t w_[kMaxLevels] = {}, h_[kMaxLevels] = {};
};

// RGB8 bilinear blend of the 2 x 2 texels at p00 (row stride in bytes; dx = 3 bytes to the
// right neighbour, 0 when clamped) into out[3], in the 0..255 range.
inline void bilerp_rgb8(const std::uint8_t* p00, std::size_t stride, std::size_t dx,
                        std::size_t dy, float fx, float fy, float* out) {
    const std::uint8_t* p10 = p00 + dx;
    const std::uint8_t* p01 = p00 + dy * stride;
    const std::uint8_t* p11 = p01 + dx;
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    for (int c = 0; c < 3; ++c)
        out[c] = w00 * p00[c] + w10 * p10[c] + w01 * p01[c] + w11 * p11[c];
}

#if defined(__SSE2__)
// bilerp_rgb8 with dx = 3, dy = 1 on four lanes at once: the same products summed in the
// same order, so the same floats. Each texel load reads 4 bytes (RGB and the next byte,
// whose lane is ignored), so one byte past p00 + stride + 5 must be readable; it stores 4
// floats at out, the fourth of them garbage for the caller to overwrite or ignore.
inline void bilerp_rgb8_wide(const std::uint8_t* p00, std::size_t stride, float fx, float fy,
                             float* out) {
    auto texel = [](const std::uint8_t* p) {
        std::int32_t bytes;
        std::memcpy(&bytes, p, 4);
        const __m128i zero = _mm_setzero_si128();
        const __m128i b = _mm_cvtsi32_si128(bytes);
        return _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(b, zero), zero));
    };
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    __m128 c = _mm_mul_ps(_mm_set1_ps(w00), texel(p00));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w10), texel(p00 + 3)));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w01), texel(p00 + stride)));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w11), texel(p00 + stride + 3)));
    _mm_storeu_ps(out, c);
}
#endif

// The same blend from four texels held as words (r | g << 8 | b << 16: a BC1 palette entry),
// t00, t10, t01, t11: the same products summed in the same order as bilerp_rgb8 and
// bilerp_rgb8_wide, so the same floats; writes out[3] only. bilerp_words_scalar is its
// plain C++ twin.
inline void bilerp_words_scalar(const std::uint32_t* t, float fx, float fy, float* out) {
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    for (int k = 0; k < 3; ++k) {
        const unsigned s = 8 * k;
        out[k] = w00 * float((t[0] >> s) & 255u) + w10 * float((t[1] >> s) & 255u) +
                 w01 * float((t[2] >> s) & 255u) + w11 * float((t[3] >> s) & 255u);
    }
}
inline void bilerp_words(const std::uint32_t* t, float fx, float fy, float* out) {
#if defined(__SSE2__)
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    auto texel = [](std::uint32_t bytes) {
        const __m128i zero = _mm_setzero_si128();
        const __m128i b = _mm_cvtsi32_si128(static_cast<int>(bytes));
        return _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(b, zero), zero));
    };
    __m128 c = _mm_mul_ps(_mm_set1_ps(w00), texel(t[0]));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w10), texel(t[1])));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w01), texel(t[2])));
    c = _mm_add_ps(c, _mm_mul_ps(_mm_set1_ps(w11), texel(t[3])));
    alignas(16) float lanes[4];
    _mm_store_ps(lanes, c);
    out[0] = lanes[0], out[1] = lanes[1], out[2] = lanes[2];
#else
    bilerp_words_scalar(t, fx, fy, out);
#endif
}

// blend_levels_rgb8's plain C++ twin (the same products and sums, so the same floats).
inline void blend_levels_rgb8_scalar(const std::uint8_t* fine, const std::uint8_t* coarse, std::size_t row,
                                     float fx0, float fy0, float fx1, float fy1, float blend, float* out) {
    float c[3];
    bilerp_rgb8(fine, row, 3, 1, fx0, fy0, out);
    bilerp_rgb8(coarse, row, 3, 1, fx1, fy1, c);
    for (int k = 0; k < 3; ++k) out[k] += blend * (c[k] - out[k]);
}

// Both levels' bilerp_rgb8 of one sample and sample_trilinear's blend, out[0..2]; `wide`
// also writes a garbage out[3] (the next sample's first channel, written after).
inline void blend_levels_rgb8(const std::uint8_t* fine, const std::uint8_t* coarse, std::size_t row,
                              float fx0, float fy0, float fx1, float fy1, float blend, bool wide,
                              float* out) {
#if defined(__AVX2__)
    // The two footprints in the two halves of 8 lanes: the same products and sums per half.
    auto texels = [](const std::uint8_t* a, const std::uint8_t* b) {
        std::int32_t x, y;
        std::memcpy(&x, a, 4);
        std::memcpy(&y, b, 4);
        return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_insert_epi32(_mm_cvtsi32_si128(x), y, 1)));
    };
    auto halves = [](float a, float b) {
        return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_set1_ps(a)), _mm_set1_ps(b), 1);
    };
    const __m256 one = _mm256_set1_ps(1.0f), fx = halves(fx0, fx1), fy = halves(fy0, fy1);
    const __m256 gx = _mm256_sub_ps(one, fx), gy = _mm256_sub_ps(one, fy);
    __m256 c = _mm256_mul_ps(_mm256_mul_ps(gx, gy), texels(fine, coarse));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(fx, gy), texels(fine + 3, coarse + 3)));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(gx, fy), texels(fine + row, coarse + row)));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(fx, fy), texels(fine + row + 3, coarse + row + 3)));
    const __m128 f = _mm256_castps256_ps128(c), g = _mm256_extractf128_ps(c, 1);
    const __m128 r = _mm_add_ps(f, _mm_mul_ps(_mm_set1_ps(blend), _mm_sub_ps(g, f)));
    if (wide) {
        _mm_storeu_ps(out, r);
    } else {
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, r);
        out[0] = lanes[0], out[1] = lanes[1], out[2] = lanes[2];
    }
#else
    (void)wide;
    blend_levels_rgb8_scalar(fine, coarse, row, fx0, fy0, fx1, fy1, blend, out);
#endif
}

}  // namespace gigascroll

// A lane type for the display pass's vector code, in the manner of Embree's vfloat<N> and
// OpenImageIO's simd.h: Lanes<W>::F (floats), ::I (int32) and ::M (a mask) of W lanes, W = 1
// (plain C++), 8 (AVX2) or 16 (AVX-512), so that one text says a step for every width. Each
// operation is one instruction of the width (or the C++ operator at W = 1) with IEEE single
// rounding, so a step gives the same floats at every width; tests run each width the host has
// (kWidest and below) against W = 1. Only what the display pass uses is here.
//
// Why not Google Highway (Debian's libhwy-dev): its runtime dispatch would let one build pick
// the best width on any x86-64, but the display pass's steps run inside Embree packets of 16
// and feed 16-lane samplers (TrilinearLanes); a W-generic type with the width fixed at compile
// time keeps the 16 lanes of a packet in one register at AVX-512 and two at AVX2 without a
// dispatch per packet, and the whole type is this file.
#pragma once
#include <cmath>
#include <cstdint>
#if defined(__AVX2__) || defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace gigascroll {
namespace display {

template <int W>
struct Lanes;

// W = 1: plain C++ (every host; the sanitizer builds).
template <>
struct Lanes<1> {
    static constexpr int kWidth = 1;
    struct M {
        bool v;
        friend M operator&(M a, M b) { return {a.v && b.v}; }
        friend M operator|(M a, M b) { return {a.v || b.v}; }
        friend M operator!(M a) { return {!a.v}; }
    };
    struct I {
        std::int32_t v;
        I() = default;
        I(std::int32_t x) : v(x) {}
        static I load(const std::int32_t* p) { return I(*p); }
        void store(std::int32_t* p) const { *p = v; }
        void store(std::uint32_t* p) const { *p = std::uint32_t(v); }
        friend I operator+(I a, I b) { return I(std::int32_t(std::uint32_t(a.v) + std::uint32_t(b.v))); }
        friend I operator*(I a, I b) { return I(std::int32_t(std::uint32_t(a.v) * std::uint32_t(b.v))); }
        friend M nonzero(I a) { return {a.v != 0}; }
    };
    struct F {
        float v;
        F() = default;
        F(float x) : v(x) {}
        static F load(const float* p) { return F(*p); }
        void store(float* p) const { *p = v; }
        friend F operator+(F a, F b) { return F(a.v + b.v); }
        friend F operator-(F a, F b) { return F(a.v - b.v); }
        friend F operator*(F a, F b) { return F(a.v * b.v); }
        friend F operator/(F a, F b) { return F(a.v / b.v); }
        friend F floor(F a) { return F(std::floor(a.v)); }
        friend M operator<(F a, F b) { return {a.v < b.v}; }
        friend M operator<=(F a, F b) { return {a.v <= b.v}; }
        friend M operator>(F a, F b) { return {a.v > b.v}; }
        friend M operator>=(F a, F b) { return {a.v >= b.v}; }
        // Truncation toward zero (exact for integral values in int32's range).
        friend I to_int(F a) { return I(std::int32_t(a.v)); }
    };
    static I select(M m, I a, I b) { return m.v ? a : b; }
    static F select(M m, F a, F b) { return m.v ? a : b; }
};

#if defined(__AVX2__)
template <>
struct Lanes<8> {
    static constexpr int kWidth = 8;
    struct M {
        __m256 v;  // all ones or zero per lane
        friend M operator&(M a, M b) { return {_mm256_and_ps(a.v, b.v)}; }
        friend M operator|(M a, M b) { return {_mm256_or_ps(a.v, b.v)}; }
        friend M operator!(M a) { return {_mm256_xor_ps(a.v, _mm256_castsi256_ps(_mm256_set1_epi32(-1)))}; }
    };
    struct I {
        __m256i v;
        I() = default;
        I(__m256i x) : v(x) {}
        I(std::int32_t x) : v(_mm256_set1_epi32(x)) {}
        static I load(const std::int32_t* p) { return I(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))); }
        void store(std::int32_t* p) const { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
        void store(std::uint32_t* p) const { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
        friend I operator+(I a, I b) { return I(_mm256_add_epi32(a.v, b.v)); }
        friend I operator*(I a, I b) { return I(_mm256_mullo_epi32(a.v, b.v)); }
        friend M nonzero(I a) {
            return {_mm256_xor_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(a.v, _mm256_setzero_si256())),
                                  _mm256_castsi256_ps(_mm256_set1_epi32(-1)))};
        }
    };
    struct F {
        __m256 v;
        F() = default;
        F(__m256 x) : v(x) {}
        F(float x) : v(_mm256_set1_ps(x)) {}
        static F load(const float* p) { return F(_mm256_loadu_ps(p)); }
        void store(float* p) const { _mm256_storeu_ps(p, v); }
        friend F operator+(F a, F b) { return F(_mm256_add_ps(a.v, b.v)); }
        friend F operator-(F a, F b) { return F(_mm256_sub_ps(a.v, b.v)); }
        friend F operator*(F a, F b) { return F(_mm256_mul_ps(a.v, b.v)); }
        friend F operator/(F a, F b) { return F(_mm256_div_ps(a.v, b.v)); }
        friend F floor(F a) { return F(_mm256_floor_ps(a.v)); }
        friend M operator<(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)}; }
        friend M operator<=(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)}; }
        friend M operator>(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ)}; }
        friend M operator>=(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ)}; }
        friend I to_int(F a) { return I(_mm256_cvttps_epi32(a.v)); }
    };
    static I select(M m, I a, I b) {
        return I(_mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b.v), _mm256_castsi256_ps(a.v), m.v)));
    }
    static F select(M m, F a, F b) { return F(_mm256_blendv_ps(b.v, a.v, m.v)); }
};
#endif

#if defined(__AVX512F__)
template <>
struct Lanes<16> {
    static constexpr int kWidth = 16;
    struct M {
        __mmask16 v;
        friend M operator&(M a, M b) { return {__mmask16(a.v & b.v)}; }
        friend M operator|(M a, M b) { return {__mmask16(a.v | b.v)}; }
        friend M operator!(M a) { return {__mmask16(~a.v)}; }
    };
    struct I {
        __m512i v;
        I() = default;
        I(__m512i x) : v(x) {}
        I(std::int32_t x) : v(_mm512_set1_epi32(x)) {}
        static I load(const std::int32_t* p) { return I(_mm512_loadu_si512(p)); }
        void store(std::int32_t* p) const { _mm512_storeu_si512(p, v); }
        void store(std::uint32_t* p) const { _mm512_storeu_si512(p, v); }
        friend I operator+(I a, I b) { return I(_mm512_add_epi32(a.v, b.v)); }
        friend I operator*(I a, I b) { return I(_mm512_mullo_epi32(a.v, b.v)); }
        friend M nonzero(I a) { return {_mm512_test_epi32_mask(a.v, a.v)}; }
    };
    struct F {
        __m512 v;
        F() = default;
        F(__m512 x) : v(x) {}
        F(float x) : v(_mm512_set1_ps(x)) {}
        static F load(const float* p) { return F(_mm512_loadu_ps(p)); }
        void store(float* p) const { _mm512_storeu_ps(p, v); }
        friend F operator+(F a, F b) { return F(_mm512_add_ps(a.v, b.v)); }
        friend F operator-(F a, F b) { return F(_mm512_sub_ps(a.v, b.v)); }
        friend F operator*(F a, F b) { return F(_mm512_mul_ps(a.v, b.v)); }
        friend F operator/(F a, F b) { return F(_mm512_div_ps(a.v, b.v)); }
        friend F floor(F a) { return F(_mm512_roundscale_ps(a.v, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC)); }
        friend M operator<(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ)}; }
        friend M operator<=(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ)}; }
        friend M operator>(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ)}; }
        friend M operator>=(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ)}; }
        friend I to_int(F a) { return I(_mm512_cvttps_epi32(a.v)); }
    };
    static I select(M m, I a, I b) { return I(_mm512_mask_blend_epi32(m.v, b.v, a.v)); }
    static F select(M m, F a, F b) { return F(_mm512_mask_blend_ps(m.v, b.v, a.v)); }
};
#endif

// The widest lanes this build has.
#if defined(__AVX512F__)
inline constexpr int kWidest = 16;
#elif defined(__AVX2__)
inline constexpr int kWidest = 8;
#else
inline constexpr int kWidest = 1;
#endif

}  // namespace display
}  // namespace gigascroll

// A lane type for the vector code (the display pass's steps, the virtual texture's lanes), in
// the manner of Embree's vfloat<N> and OpenImageIO's simd.h: Lanes<W>::F (floats), ::I (int32)
// and ::M (a mask) of W lanes, W = 1 (plain C++), 8 (AVX2) or 16 (AVX-512), so that one text
// says a step for every width. Each operation is one instruction of the width (or the C++
// operator at W = 1) with IEEE single rounding, so a step gives the same floats at every
// width; tests run each width the host has (kWidest and below) against W = 1. Only what the
// code uses is here. The few operations a lane type cannot say as arithmetic (a table lookup
// across lanes, the hardware's estimates) are functions of their own below the types, each
// with its W = 1 twin.
//
// Why not Google Highway (Debian's libhwy-dev): see docs/lanes.md. In short, the steps run
// inside Embree packets of 16 and feed 16-lane samplers; a type with the width fixed at compile
// time keeps a packet in one register at AVX-512 and two at AVX2 without a dispatch per
// packet, the generated code is the hand-written intrinsics' instruction for instruction (the
// frames hash equal), and the whole type is this file.
#pragma once
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#if defined(__AVX2__) || defined(__AVX512F__)
#include <immintrin.h>
#elif defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace gigascroll {

template <int W>
struct Lanes;

// W = 1: plain C++ (every host).
template <>
struct Lanes<1> {
    static constexpr int kWidth = 1;
    struct M {
        bool v;
        friend M operator&(M a, M b) { return {a.v && b.v}; }
        friend M operator|(M a, M b) { return {a.v || b.v}; }
        friend M operator^(M a, M b) { return {a.v != b.v}; }
        friend M operator!(M a) { return {!a.v}; }
        // The lanes set, lane k in bit k.
        unsigned bits() const { return v ? 1u : 0u; }
    };
    struct I {
        std::int32_t v;
        I() = default;
        I(std::int32_t x) : v(x) {}
        static I load(const std::int32_t* p) { return I(*p); }
        static I load(const std::uint32_t* p) { return I(std::int32_t(*p)); }
        void store(std::int32_t* p) const { *p = v; }
        void store(std::uint32_t* p) const { *p = std::uint32_t(v); }
        friend I operator+(I a, I b) { return I(std::int32_t(std::uint32_t(a.v) + std::uint32_t(b.v))); }
        friend I operator-(I a, I b) { return I(std::int32_t(std::uint32_t(a.v) - std::uint32_t(b.v))); }
        friend I operator*(I a, I b) { return I(std::int32_t(std::uint32_t(a.v) * std::uint32_t(b.v))); }
        friend I operator&(I a, I b) { return I(a.v & b.v); }
        friend I operator|(I a, I b) { return I(a.v | b.v); }
        // Logical shifts (zeros in).
        friend I srl(I a, int s) { return I(std::int32_t(std::uint32_t(a.v) >> s)); }
        friend I min(I a, I b) { return I(a.v < b.v ? a.v : b.v); }
        friend I max(I a, I b) { return I(a.v > b.v ? a.v : b.v); }
        friend M operator==(I a, I b) { return {a.v == b.v}; }
        friend M operator!=(I a, I b) { return {a.v != b.v}; }
        friend M operator>(I a, I b) { return {a.v > b.v}; }
        friend M operator<=(I a, I b) { return {a.v <= b.v}; }
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
        // The instructions' min and max: a < b ? a : b and a > b ? a : b (b where NaN).
        friend F min(F a, F b) { return F(a.v < b.v ? a.v : b.v); }
        friend F max(F a, F b) { return F(a.v > b.v ? a.v : b.v); }
        // a b + c and c - a b, each rounded once.
        friend F fma(F a, F b, F c) { return F(std::fma(a.v, b.v, c.v)); }
        friend F fnma(F a, F b, F c) { return F(std::fma(-a.v, b.v, c.v)); }
        friend M operator<(F a, F b) { return {a.v < b.v}; }
        friend M operator<=(F a, F b) { return {a.v <= b.v}; }
        friend M operator>(F a, F b) { return {a.v > b.v}; }
        friend M operator>=(F a, F b) { return {a.v >= b.v}; }
        // Truncation toward zero (exact for integral values in int32's range).
        friend I to_int(F a) { return I(std::int32_t(a.v)); }
        friend I bits(F a) { return I(std::bit_cast<std::int32_t>(a.v)); }
    };
    static I select(M m, I a, I b) { return m.v ? a : b; }
    static F select(M m, F a, F b) { return m.v ? a : b; }
    // An int32's float (rounded) and the float of int32 bits.
    static F to_float(I a) { return F(float(a.v)); }
    static F from_bits(I a) { return F(std::bit_cast<float>(a.v)); }
};

#if defined(__AVX2__)
template <>
struct Lanes<8> {
    static constexpr int kWidth = 8;
    struct M {
        __m256 v;  // all ones or zero per lane
        friend M operator&(M a, M b) { return {_mm256_and_ps(a.v, b.v)}; }
        friend M operator|(M a, M b) { return {_mm256_or_ps(a.v, b.v)}; }
        friend M operator^(M a, M b) { return {_mm256_xor_ps(a.v, b.v)}; }
        friend M operator!(M a) { return {_mm256_xor_ps(a.v, _mm256_castsi256_ps(_mm256_set1_epi32(-1)))}; }
        unsigned bits() const { return unsigned(_mm256_movemask_ps(v)); }
    };
    struct I {
        __m256i v;
        I() = default;
        I(__m256i x) : v(x) {}
        I(std::int32_t x) : v(_mm256_set1_epi32(x)) {}
        static I load(const std::int32_t* p) { return I(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))); }
        static I load(const std::uint32_t* p) { return I(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))); }
        void store(std::int32_t* p) const { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
        void store(std::uint32_t* p) const { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
        friend I operator+(I a, I b) { return I(_mm256_add_epi32(a.v, b.v)); }
        friend I operator-(I a, I b) { return I(_mm256_sub_epi32(a.v, b.v)); }
        friend I operator*(I a, I b) { return I(_mm256_mullo_epi32(a.v, b.v)); }
        friend I operator&(I a, I b) { return I(_mm256_and_si256(a.v, b.v)); }
        friend I operator|(I a, I b) { return I(_mm256_or_si256(a.v, b.v)); }
        friend I srl(I a, int s) { return I(_mm256_srli_epi32(a.v, s)); }
        friend I min(I a, I b) { return I(_mm256_min_epi32(a.v, b.v)); }
        friend I max(I a, I b) { return I(_mm256_max_epi32(a.v, b.v)); }
        friend M operator==(I a, I b) { return {_mm256_castsi256_ps(_mm256_cmpeq_epi32(a.v, b.v))}; }
        friend M operator!=(I a, I b) { return !(a == b); }
        friend M operator>(I a, I b) { return {_mm256_castsi256_ps(_mm256_cmpgt_epi32(a.v, b.v))}; }
        friend M operator<=(I a, I b) { return !(a > b); }
        friend M nonzero(I a) { return !(a == I(0)); }
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
        friend F min(F a, F b) { return F(_mm256_min_ps(a.v, b.v)); }
        friend F max(F a, F b) { return F(_mm256_max_ps(a.v, b.v)); }
        friend F fma(F a, F b, F c) { return F(_mm256_fmadd_ps(a.v, b.v, c.v)); }
        friend F fnma(F a, F b, F c) { return F(_mm256_fnmadd_ps(a.v, b.v, c.v)); }
        friend M operator<(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ)}; }
        friend M operator<=(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ)}; }
        friend M operator>(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ)}; }
        friend M operator>=(F a, F b) { return {_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ)}; }
        friend I to_int(F a) { return I(_mm256_cvttps_epi32(a.v)); }
        friend I bits(F a) { return I(_mm256_castps_si256(a.v)); }
    };
    static I select(M m, I a, I b) {
        return I(_mm256_castps_si256(_mm256_blendv_ps(_mm256_castsi256_ps(b.v), _mm256_castsi256_ps(a.v), m.v)));
    }
    static F select(M m, F a, F b) { return F(_mm256_blendv_ps(b.v, a.v, m.v)); }
    static F to_float(I a) { return F(_mm256_cvtepi32_ps(a.v)); }
    static F from_bits(I a) { return F(_mm256_castsi256_ps(a.v)); }
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
        friend M operator^(M a, M b) { return {__mmask16(a.v ^ b.v)}; }
        friend M operator!(M a) { return {__mmask16(~a.v)}; }
        unsigned bits() const { return unsigned(v); }
    };
    struct I {
        __m512i v;
        I() = default;
        I(__m512i x) : v(x) {}
        I(std::int32_t x) : v(_mm512_set1_epi32(x)) {}
        static I load(const std::int32_t* p) { return I(_mm512_loadu_si512(p)); }
        static I load(const std::uint32_t* p) { return I(_mm512_loadu_si512(p)); }
        void store(std::int32_t* p) const { _mm512_storeu_si512(p, v); }
        void store(std::uint32_t* p) const { _mm512_storeu_si512(p, v); }
        friend I operator+(I a, I b) { return I(_mm512_add_epi32(a.v, b.v)); }
        friend I operator-(I a, I b) { return I(_mm512_sub_epi32(a.v, b.v)); }
        friend I operator*(I a, I b) { return I(_mm512_mullo_epi32(a.v, b.v)); }
        friend I operator&(I a, I b) { return I(_mm512_and_si512(a.v, b.v)); }
        friend I operator|(I a, I b) { return I(_mm512_or_si512(a.v, b.v)); }
        friend I srl(I a, int s) { return I(_mm512_srli_epi32(a.v, unsigned(s))); }
        friend I min(I a, I b) { return I(_mm512_min_epi32(a.v, b.v)); }
        friend I max(I a, I b) { return I(_mm512_max_epi32(a.v, b.v)); }
        friend M operator==(I a, I b) { return {_mm512_cmpeq_epi32_mask(a.v, b.v)}; }
        friend M operator!=(I a, I b) { return {_mm512_cmpneq_epi32_mask(a.v, b.v)}; }
        friend M operator>(I a, I b) { return {_mm512_cmpgt_epi32_mask(a.v, b.v)}; }
        friend M operator<=(I a, I b) { return {_mm512_cmple_epi32_mask(a.v, b.v)}; }
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
        friend F min(F a, F b) { return F(_mm512_min_ps(a.v, b.v)); }
        friend F max(F a, F b) { return F(_mm512_max_ps(a.v, b.v)); }
        friend F fma(F a, F b, F c) { return F(_mm512_fmadd_ps(a.v, b.v, c.v)); }
        friend F fnma(F a, F b, F c) { return F(_mm512_fnmadd_ps(a.v, b.v, c.v)); }
        friend M operator<(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ)}; }
        friend M operator<=(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ)}; }
        friend M operator>(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ)}; }
        friend M operator>=(F a, F b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ)}; }
        friend I to_int(F a) { return I(_mm512_cvttps_epi32(a.v)); }
        friend I bits(F a) { return I(_mm512_castps_si512(a.v)); }
    };
    static I select(M m, I a, I b) { return I(_mm512_mask_blend_epi32(m.v, b.v, a.v)); }
    static F select(M m, F a, F b) { return F(_mm512_mask_blend_ps(m.v, b.v, a.v)); }
    static F to_float(I a) { return F(_mm512_cvtepi32_ps(a.v)); }
    static F from_bits(I a) { return F(_mm512_castsi512_ps(a.v)); }
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

// Whether any (every) lane of a mask is set.
template <int W>
bool any(typename Lanes<W>::M m) {
    return m.bits() != 0;
}
template <int W>
bool all(typename Lanes<W>::M m) {
    return m.bits() == (W == 32 ? ~0u : (1u << W) - 1);
}

// --- What arithmetic cannot say: one function each, per width, with its W = 1 twin. ---

// The lanes whose float is not a positive normal number (zero, subnormal, infinite, NaN or
// negative): the exponent field 0 or 255, or the sign set. One instruction at 16 lanes.
inline Lanes<1>::M not_positive_normal(Lanes<1>::F x) {
    const std::uint32_t b = std::bit_cast<std::uint32_t>(x.v), e = (b >> 23) & 0xff;
    return {e == 0 || e == 0xff || (b >> 31) != 0};
}
#if defined(__AVX2__)
inline Lanes<8>::M not_positive_normal(Lanes<8>::F x) {
    using I = Lanes<8>::I;
    const I e = srl(bits(x), 23) & I(0xff);
    return (e == I(0)) | (e == I(0xff)) | (I(0) > bits(x));
}
#endif
#if defined(__AVX512F__) && defined(__AVX512DQ__)
inline Lanes<16>::M not_positive_normal(Lanes<16>::F x) {
    // fpclass: QNaN, +0, -0, +inf, -inf, subnormal, negative, SNaN.
    return {_mm512_fpclass_ps_mask(x.v, 0x01 | 0x02 | 0x04 | 0x08 | 0x10 | 0x20 | 0x40 | 0x80)};
}
#endif

// The lanes whose float is not finite (infinite or NaN).
inline Lanes<1>::M not_finite(Lanes<1>::F x) { return {!std::isfinite(x.v)}; }
#if defined(__AVX2__)
inline Lanes<8>::M not_finite(Lanes<8>::F x) {
    using I = Lanes<8>::I;
    return (srl(bits(x), 23) & I(0xff)) == I(0xff);
}
#endif
#if defined(__AVX512F__) && defined(__AVX512DQ__)
inline Lanes<16>::M not_finite(Lanes<16>::F x) { return {_mm512_fpclass_ps_mask(x.v, 0x01 | 0x08 | 0x10 | 0x80)}; }
#endif

// 1 / x to about 2^-28: the hardware's 14-bit reciprocal estimate (AVX-512's rcp14, the same
// at every width on a host that has it) and one Newton step; a plain division where the
// host has no rcp14 (then the same at every width of that host).
inline Lanes<1>::F reciprocal(Lanes<1>::F x) {
#if defined(__AVX512F__)
    const float r = _mm_cvtss_f32(_mm_rcp14_ss(_mm_setzero_ps(), _mm_set_ss(x.v)));
    return Lanes<1>::F(std::fma(r, std::fma(-x.v, r, 1.0f), r));
#else
    return Lanes<1>::F(1.0f / x.v);
#endif
}
#if defined(__AVX2__)
inline Lanes<8>::F reciprocal(Lanes<8>::F x) {
#if defined(__AVX512VL__)
    const Lanes<8>::F r(_mm256_rcp14_ps(x.v));
    return fma(r, fnma(x, r, 1.0f), r);
#else
    return Lanes<8>::F(1.0f) / x;
#endif
}
#endif
#if defined(__AVX512F__)
inline Lanes<16>::F reciprocal(Lanes<16>::F x) {
    const Lanes<16>::F r(_mm512_rcp14_ps(x.v));
    return fma(r, fnma(x, r, 1.0f), r);
}
#endif

// The hardware's 12-bit estimate of 1 / sqrt(x) (SSE's rsqrt, which gives the same estimate
// for one lane as for eight; the 16-lane form takes it as two eight-lane halves so that
// every width has the same), 1 / sqrt(x) where the host has no SSE.
inline Lanes<1>::F rsqrt_estimate(Lanes<1>::F x) {
#if defined(__SSE__)
    return Lanes<1>::F(_mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(x.v))));
#else
    return Lanes<1>::F(1.0f / std::sqrt(x.v));
#endif
}
#if defined(__AVX2__)
inline Lanes<8>::F rsqrt_estimate(Lanes<8>::F x) { return Lanes<8>::F(_mm256_rsqrt_ps(x.v)); }
#endif
#if defined(__AVX512F__)
inline Lanes<16>::F rsqrt_estimate(Lanes<16>::F x) {
    const __m256 lo = _mm256_rsqrt_ps(_mm512_castps512_ps256(x.v));
    const __m256 hi = _mm256_rsqrt_ps(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(x.v), 1)));
    return Lanes<16>::F(_mm512_castpd_ps(_mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_castps_pd(lo)),
                                                            _mm256_castps_pd(hi), 1)));
}
#endif

// table[index] per lane from a table of 16 floats (index in [0, 16)): one in-register
// permute at 16 lanes, two and a blend at 8.
inline Lanes<1>::F lookup16(const float* table, Lanes<1>::I index) { return Lanes<1>::F(table[index.v]); }
#if defined(__AVX2__)
inline Lanes<8>::F lookup16(const float* table, Lanes<8>::I index) {
    const __m256 lo = _mm256_permutevar8x32_ps(_mm256_loadu_ps(table), index.v);
    const __m256 hi = _mm256_permutevar8x32_ps(_mm256_loadu_ps(table + 8), index.v);
    return Lanes<8>::F(_mm256_blendv_ps(lo, hi, _mm256_castsi256_ps(_mm256_cmpgt_epi32(index.v, _mm256_set1_epi32(7)))));
}
#endif
#if defined(__AVX512F__)
inline Lanes<16>::F lookup16(const float* table, Lanes<16>::I index) {
    return Lanes<16>::F(_mm512_permutexvar_ps(index.v, _mm512_loadu_ps(table)));
}
#endif

// The first n lanes of x stored at p (n <= W; a whole vector: a plain store).
inline void store_first(Lanes<1>::F x, float* p, unsigned n) {
    if (n) *p = x.v;
}
#if defined(__AVX2__)
inline void store_first(Lanes<8>::F x, float* p, unsigned n) {
    if (n >= 8) return x.store(p);
    alignas(32) float t[8];
    _mm256_store_ps(t, x.v);
    for (unsigned k = 0; k < n; ++k) p[k] = t[k];
}
#endif
#if defined(__AVX512F__)
inline void store_first(Lanes<16>::F x, float* p, unsigned n) {
    if (n >= 16)  // a plain store: a masked one costs twice as much
        _mm512_storeu_ps(p, x.v);
    else
        _mm512_mask_storeu_ps(p, __mmask16((1u << n) - 1), x.v);
}
#endif

// The mask whose lane k is bit k of bits.
template <int W>
typename Lanes<W>::M mask_of(unsigned bits);
template <>
inline Lanes<1>::M mask_of<1>(unsigned bits) { return {(bits & 1u) != 0}; }
#if defined(__AVX2__)
template <>
inline Lanes<8>::M mask_of<8>(unsigned bits) {
    using I = Lanes<8>::I;
    return nonzero(I(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)) & I(std::int32_t(bits)));
}
#endif
#if defined(__AVX512F__)
template <>
inline Lanes<16>::M mask_of<16>(unsigned bits) { return {__mmask16(bits)}; }
#endif

// Gathers: the 4-byte word at base + 4 index per lane where m is set, src's lane elsewhere
// (the lanes not set read nothing). base is untyped: the lattice reads the low words of
// 64-bit offsets and the floats of Vec3f arrays.
inline Lanes<1>::F gather(Lanes<1>::F src, const void* base, Lanes<1>::I index, Lanes<1>::M m) {
    if (!m.v) return src;
    float x;
    std::memcpy(&x, static_cast<const char*>(base) + 4 * std::ptrdiff_t(index.v), 4);
    return Lanes<1>::F(x);
}
inline Lanes<1>::I gather(Lanes<1>::I src, const void* base, Lanes<1>::I index, Lanes<1>::M m) {
    if (!m.v) return src;
    std::int32_t x;
    std::memcpy(&x, static_cast<const char*>(base) + 4 * std::ptrdiff_t(index.v), 4);
    return Lanes<1>::I(x);
}
#if defined(__AVX2__)
inline Lanes<8>::F gather(Lanes<8>::F src, const void* base, Lanes<8>::I index, Lanes<8>::M m) {
    return Lanes<8>::F(_mm256_mask_i32gather_ps(src.v, static_cast<const float*>(base), index.v, m.v, 4));
}
inline Lanes<8>::I gather(Lanes<8>::I src, const void* base, Lanes<8>::I index, Lanes<8>::M m) {
    return Lanes<8>::I(_mm256_mask_i32gather_epi32(src.v, static_cast<const int*>(base), index.v,
                                                   _mm256_castps_si256(m.v), 4));
}
#endif
#if defined(__AVX512F__)
inline Lanes<16>::F gather(Lanes<16>::F src, const void* base, Lanes<16>::I index, Lanes<16>::M m) {
    return Lanes<16>::F(_mm512_mask_i32gather_ps(src.v, m.v, index.v, base, 4));
}
inline Lanes<16>::I gather(Lanes<16>::I src, const void* base, Lanes<16>::I index, Lanes<16>::M m) {
    return Lanes<16>::I(_mm512_mask_i32gather_epi32(src.v, m.v, index.v, base, 4));
}
#endif

// The 4-byte word at base + offset bytes per lane (any alignment): a texel's RGB and the
// next byte, where the sampler reads a footprint's corners.
inline Lanes<1>::I gather_bytes(const std::uint8_t* base, Lanes<1>::I offset) {
    std::int32_t x;
    std::memcpy(&x, base + offset.v, 4);
    return Lanes<1>::I(x);
}
#if defined(__AVX2__)
inline Lanes<8>::I gather_bytes(const std::uint8_t* base, Lanes<8>::I offset) {
    return Lanes<8>::I(_mm256_i32gather_epi32(reinterpret_cast<const int*>(base), offset.v, 1));
}
#endif
#if defined(__AVX512F__)
inline Lanes<16>::I gather_bytes(const std::uint8_t* base, Lanes<16>::I offset) {
    return Lanes<16>::I(_mm512_i32gather_epi32(offset.v, static_cast<const void*>(base), 1));
}
#endif

// Lane k's int32, in registers (a vector just stored and read back as one lane waits for the
// store: the loads of a wide store's parts do not forward).
inline std::int32_t lane_value(Lanes<1>::I x, int) { return x.v; }
#if defined(__AVX2__)
inline std::int32_t lane_value(Lanes<8>::I x, int k) {
    return _mm_cvtsi128_si32(_mm256_castsi256_si128(_mm256_permutevar8x32_epi32(x.v, _mm256_set1_epi32(k))));
}
#endif
#if defined(__AVX512F__)
inline std::int32_t lane_value(Lanes<16>::I x, int k) {
    return _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(_mm512_set1_epi32(k), x.v)));
}
#endif

}  // namespace gigascroll

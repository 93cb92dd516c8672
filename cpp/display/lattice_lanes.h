// The "light" step of the display pass on a baked lattice (display/baked_lattice.h): a
// packet's 16 lanes lit from the lattice points around each lane's hit.
#pragma once
#include <embree3/rtcore.h>

#include <bit>
#include <cstdint>
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "common/vec3.h"
#include "display/baked_lattice.h"

namespace gigascroll {
namespace display {

// A packet's light in SoA lanes: per lane the irradiance E, the albedo and the emission.
struct LaneLight {
    alignas(64) float E[3][16];  // irradiance, per channel
    alignas(64) float a[3][16];  // albedo
    alignas(64) float M[3][16];  // emission
};

// The baked lattice at a packet's 16 lanes in two steps, so that the lattice points' cache
// lines (the blend waited for them) arrive while the packet's other work runs: locate() finds
// each lane's three points and weights and fetches the points, blend() reads them later.
struct LatticeLanes {
    alignas(64) const Vec3f* corner[3][16];
    alignas(64) float weight[3][16];
    alignas(64) std::uint32_t tri[16];
    alignas(64) std::int32_t front[16];

    // Lanes with hit[k] != 0 (Embree's geometry, primitive, barycentrics and geometric normal
    // Ng, and back[k] != 0 where the ray runs along Ng, i.e. sees the side Ng points away
    // from): Gallery's lattice_lerp (the clamps, the cell, the sub-triangle
    // and its weights) in straight loops over the lanes, lanes without a hit reading
    // triangle 0 (ignored). No trapping math, as Gallery's lattice_cells: with it GCC keeps
    // the selects as branches.
    [[gnu::optimize("no-trapping-math"), gnu::noinline]]
    void locate(const BakedLattice& b, const RTCHit16& h, const int* __restrict hit,
                const std::int32_t* __restrict back) {
        const unsigned* __restrict geom_in = h.geomID;
        const unsigned* __restrict prim_in = h.primID;
        const float* __restrict b1_in = h.u;
        const float* __restrict b2_in = h.v;
        alignas(64) std::int32_t segments[16], cell_i[16], cell_j[16], upper_of[16];
        // A lane without a hit holds whatever Embree left in its u, v (NaN or huge after a
        // miss): its cell would index far outside the lattice, and blend() reads every lane.
        alignas(64) float b1[16], b2[16];
        for (int k = 0; k < 16; ++k) {
            const std::uint32_t g = hit[k] ? geom_in[k] : 0u, p = hit[k] ? prim_in[k] : 0u;
            const std::uint32_t t = b.first_triangle[g] + p;
            const Vec3f w = b.normal[t];
            tri[k] = t, segments[k] = std::int32_t(b.segments[t]);
            // The eye sees the front: the normal agrees with Embree's on the side the ray hits.
            front[k] = (w.x * h.Ng_x[k] + w.y * h.Ng_y[k] + w.z * h.Ng_z[k] > 0) != (back[k] != 0);
            b1[k] = hit[k] ? b1_in[k] : 0.0f, b2[k] = hit[k] ? b2_in[k] : 0.0f;
        }
        int k0 = 0;
#if defined(__AVX2__)
        // 8 lanes at once, the same operations (GCC vectorises the loop below with masked
        // stores, which are slow on AMD's cores). Selects are blends; min on int32 is
        // vpminsd; a float to int32 conversion truncates as the casts do.
        for (; k0 < 16; k0 += 8) {
            const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
            const __m256i n = _mm256_load_si256(reinterpret_cast<const __m256i*>(segments + k0));
            const __m256i n1 = _mm256_sub_epi32(n, _mm256_set1_epi32(1));
            __m256 c1 = _mm256_load_ps(b1 + k0), c2 = _mm256_load_ps(b2 + k0);
            // c < 0 ? 0 : (1 < c ? 1 : c)
            c1 = _mm256_blendv_ps(_mm256_blendv_ps(c1, one, _mm256_cmp_ps(one, c1, _CMP_LT_OQ)), zero,
                                  _mm256_cmp_ps(c1, zero, _CMP_LT_OQ));
            c2 = _mm256_blendv_ps(_mm256_blendv_ps(c2, one, _mm256_cmp_ps(one, c2, _CMP_LT_OQ)), zero,
                                  _mm256_cmp_ps(c2, zero, _CMP_LT_OQ));
            const __m256 s = _mm256_add_ps(c1, c2);
            const __m256 over = _mm256_cmp_ps(s, one, _CMP_GT_OQ);
            c1 = _mm256_blendv_ps(c1, _mm256_div_ps(c1, s), over);
            c2 = _mm256_blendv_ps(c2, _mm256_div_ps(c2, s), over);
            const __m256 nf = _mm256_cvtepi32_ps(n);
            const __m256 x = _mm256_mul_ps(c1, nf), y = _mm256_mul_ps(c2, nf);
            const __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(x), n1);
            const __m256i j = _mm256_min_epi32(_mm256_cvttps_epi32(y), _mm256_sub_epi32(n1, i));
            const __m256 ex = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i)), ey = _mm256_sub_ps(y, _mm256_cvtepi32_ps(j));
            __m256 fx = _mm256_blendv_ps(ex, zero, _mm256_cmp_ps(ex, zero, _CMP_LT_OQ));
            __m256 fy = _mm256_blendv_ps(ey, zero, _mm256_cmp_ps(ey, zero, _CMP_LT_OQ));
            const __m256 sum = _mm256_add_ps(fx, fy);
            const __m256 past = _mm256_cmp_ps(sum, one, _CMP_GT_OQ);
            // i + j + 2 <= n, i.e. not (i + j + 2 > n)
            const __m256i room = _mm256_xor_si256(
                _mm256_cmpgt_epi32(_mm256_add_epi32(_mm256_add_epi32(i, j), _mm256_set1_epi32(2)), n),
                _mm256_set1_epi32(-1));
            const __m256 upper = _mm256_and_ps(past, _mm256_castsi256_ps(room));
            const __m256 rescale = _mm256_andnot_ps(upper, past);
            const __m256 inv = _mm256_div_ps(one, sum);
            fx = _mm256_blendv_ps(fx, _mm256_mul_ps(fx, inv), rescale);
            fy = _mm256_blendv_ps(fy, _mm256_mul_ps(fy, inv), rescale);
            _mm256_store_si256(reinterpret_cast<__m256i*>(cell_i + k0), i);
            _mm256_store_si256(reinterpret_cast<__m256i*>(cell_j + k0), j);
            _mm256_store_si256(reinterpret_cast<__m256i*>(upper_of + k0),
                               _mm256_and_si256(_mm256_castps_si256(upper), _mm256_set1_epi32(1)));
            _mm256_store_ps(weight[0] + k0, _mm256_blendv_ps(_mm256_sub_ps(_mm256_sub_ps(one, fx), fy),
                                                            _mm256_sub_ps(_mm256_add_ps(fx, fy), one), upper));
            _mm256_store_ps(weight[1] + k0, _mm256_blendv_ps(fx, _mm256_sub_ps(one, fx), upper));
            _mm256_store_ps(weight[2] + k0, _mm256_blendv_ps(fy, _mm256_sub_ps(one, fy), upper));
        }
#endif
        for (int k = k0; k < 16; ++k) {
            const LatticeCell c = lattice_cell(segments[k], b1[k], b2[k]);
            cell_i[k] = c.i, cell_j[k] = c.j, upper_of[k] = c.upper;
            weight[0][k] = c.w0, weight[1][k] = c.w1, weight[2][k] = c.w2;
        }
        for (int k = 0; k < 16; ++k) {
            const std::uint64_t n = std::uint64_t(segments[k]);
            const std::uint64_t i = std::uint64_t(cell_i[k]), j = std::uint64_t(cell_j[k]);
            const bool upper = upper_of[k] != 0;
            // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i.
            const std::uint64_t row_i = i * (n + 1) - i * (i - 1) / 2, row_next = row_i + (n + 1 - i);
            const std::uint64_t right = row_next + j, up = row_i + j + 1;
            const std::uint64_t e0 = upper ? row_next + j + 1 : row_i + j;
            const std::uint64_t e1 = upper ? up : right, e2 = upper ? right : up;
            const Vec3f* E = (front[k] ? b.front : b.back) + b.offset[tri[k]];
            corner[0][k] = E + e0, corner[1][k] = E + e1, corner[2][k] = E + e2;
        }
        for (int k = 0; k < 16; ++k)
            if (hit[k]) {
                __builtin_prefetch(corner[0][k]);
                __builtin_prefetch(corner[1][k]);
                __builtin_prefetch(corner[2][k]);
            }
    }

    // E = E0 w0 + E1 w1 + E2 w2 per lane (lattice_lerp's order), the albedo and the emission
    // (front side only).
    void blend(const BakedLattice& b, LaneLight& __restrict out) const {
        const Vec3f zero{0.0f, 0.0f, 0.0f};
        for (int k = 0; k < 16; ++k) {
            const Vec3f a = *corner[0][k], c = *corner[1][k], d = *corner[2][k];
            const float w0 = weight[0][k], w1 = weight[1][k], w2 = weight[2][k];
            out.E[0][k] = a.x * w0 + c.x * w1 + d.x * w2;
            out.E[1][k] = a.y * w0 + c.y * w1 + d.y * w2;
            out.E[2][k] = a.z * w0 + c.z * w1 + d.z * w2;
            const std::uint32_t t = tri[k];
            const Vec3f al = b.albedo[t], em = front[k] ? b.emission[t] : zero;
            out.a[0][k] = al.x, out.a[1][k] = al.y, out.a[2][k] = al.z;
            out.M[0][k] = em.x, out.M[1][k] = em.y, out.M[2][k] = em.z;
        }
    }

#if defined(__AVX512F__) && defined(__AVX512DQ__)
// GCC 12 warns that the _mm512_undefined_* sources inside its own AVX-512 intrinsics may be
// used uninitialized (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
    // locate() and blend() in 16 lanes of one vector each: the arrays gathered with 32-bit
    // float indices (the caller checks lanes16(): 3 x the triangles and the points below
    // 2^31), the cell arithmetic as locate's, the corners' indices in uint32 (n < 2^16, so
    // i (n + 1) and a triangle's (n + 1)(n + 2) / 2 points fit). The same operations in the
    // same order as the lane loops, hence the same floats; lanes without a hit are masked
    // out of the gathers (their values are never read).
    alignas(64) std::int32_t point[3][16];  // float index of each corner in front or back
    __mmask16 hit_lanes = 0, front_lanes = 0;
    int first_lane = 0;  // the first hit lane
    bool one_triangle = false, one_cell = false;  // under every hit lane

    static bool lanes16(const BakedLattice& b) {
        constexpr std::uint64_t kLimit = (std::uint64_t(1) << 31) / 3;
        return b.triangles > 0 && b.triangles < kLimit && b.points < kLimit;
    }

    // lattice_cell's cell in lanes, of clamped barycentrics (c1, c2) on triangles of n
    // segments a side: the cell (i, j), the position in it (x, y, before locate's clamp at
    // 0), and room: whether the cell has an upper sub-triangle (i + j + 2 <= n).
    struct Cells16 {
        __m512i i, j;
        __m512 x, y;
        __mmask16 room;
    };
    static Cells16 cells16(__m512 c1, __m512 c2, __m512i n) {
        const __m512i n1 = _mm512_sub_epi32(n, _mm512_set1_epi32(1));
        const __m512 nf = _mm512_cvtepi32_ps(n);
        const __m512 x = _mm512_mul_ps(c1, nf), y = _mm512_mul_ps(c2, nf);
        Cells16 c;
        c.i = _mm512_min_epi32(_mm512_cvttps_epi32(x), n1);
        c.j = _mm512_min_epi32(_mm512_cvttps_epi32(y), _mm512_sub_epi32(n1, c.i));
        c.x = _mm512_sub_ps(x, _mm512_cvtepi32_ps(c.i)), c.y = _mm512_sub_ps(y, _mm512_cvtepi32_ps(c.j));
        c.room = _mm512_cmple_epi32_mask(_mm512_add_epi32(_mm512_add_epi32(c.i, c.j), _mm512_set1_epi32(2)), n);
        return c;
    }

    void locate16(const BakedLattice& b, const RTCHit16& h, const int* __restrict hit,
                  const std::int32_t* __restrict back) {
        const unsigned* __restrict geom_in = h.geomID;
        const unsigned* __restrict prim_in = h.primID;
        const __m512i hits = _mm512_load_si512(hit);
        const __mmask16 hm = _mm512_test_epi32_mask(hits, hits);
        hit_lanes = hm;
        const __m512i g = _mm512_maskz_loadu_epi32(hm, geom_in), p = _mm512_maskz_loadu_epi32(hm, prim_in);
        // Nearly every packet has one triangle under all its hit lanes (and one lattice cell:
        // a cell spans many pixels). Its data are then read once and broadcast: on these
        // cores a 16-lane gather costs about as much as 16 loads.
        const int k0 = std::countr_zero(unsigned(hm));  // the caller has hits
        first_lane = k0;
        const unsigned g0 = geom_in[k0], p0 = prim_in[k0];
        one_triangle = (_mm512_mask_cmpeq_epi32_mask(hm, g, _mm512_set1_epi32(int(g0))) &
                        _mm512_mask_cmpeq_epi32_mask(hm, p, _mm512_set1_epi32(int(p0)))) == hm;
        __m512i t, n, first;
        __m512 wx, wy, wz;
        if (one_triangle) {
            const std::uint32_t t0 = b.first_triangle[g0] + p0;
            const Vec3f w = b.normal[t0];
            t = _mm512_set1_epi32(int(t0));
            wx = _mm512_set1_ps(w.x), wy = _mm512_set1_ps(w.y), wz = _mm512_set1_ps(w.z);
            n = _mm512_set1_epi32(int(b.segments[t0]));
            first = _mm512_set1_epi32(int(std::uint32_t(b.offset[t0])));
        } else {
            t = _mm512_add_epi32(_mm512_i32gather_epi32(g, b.first_triangle, 4), p);
            const __m512i t3 = _mm512_mullo_epi32(t, _mm512_set1_epi32(3));
            const float* normal = &b.normal->x;
            wx = _mm512_i32gather_ps(t3, normal, 4);
            wy = _mm512_i32gather_ps(_mm512_add_epi32(t3, _mm512_set1_epi32(1)), normal, 4);
            wz = _mm512_i32gather_ps(_mm512_add_epi32(t3, _mm512_set1_epi32(2)), normal, 4);
            n = _mm512_i32gather_epi32(t, b.segments, 4);
            // The triangle's first point: the low word of offset[t] (below 2^31 / 3).
            first = _mm512_i32gather_epi32(_mm512_add_epi32(t, t), b.offset, 4);
        }
        _mm512_store_si512(tri, t);
        const __m512 facing = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(wx, _mm512_load_ps(h.Ng_x)),
                                                          _mm512_mul_ps(wy, _mm512_load_ps(h.Ng_y))),
                                            _mm512_mul_ps(wz, _mm512_load_ps(h.Ng_z)));
        const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
        const __m512i back_i = _mm512_load_si512(back);
        front_lanes = _mm512_cmp_ps_mask(facing, zero, _CMP_GT_OQ) ^ _mm512_test_epi32_mask(back_i, back_i);
        __m512 c1 = _mm512_maskz_loadu_ps(hm, h.u), c2 = _mm512_maskz_loadu_ps(hm, h.v);
        // c < 0 ? 0 : (1 < c ? 1 : c)
        c1 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(one, c1, _CMP_LT_OQ), c1, one);
        c1 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(c1, zero, _CMP_LT_OQ), c1, zero);
        c2 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(one, c2, _CMP_LT_OQ), c2, one);
        c2 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(c2, zero, _CMP_LT_OQ), c2, zero);
        const __m512 s = _mm512_add_ps(c1, c2);
        // Barycentrics past the far edge (rare: Embree's rounding) scaled back onto it.
        if (const __mmask16 over = _mm512_cmp_ps_mask(s, one, _CMP_GT_OQ)) {
            c1 = _mm512_mask_div_ps(c1, over, c1, s);
            c2 = _mm512_mask_div_ps(c2, over, c2, s);
        }
        const auto [i, j, ex, ey, room] = cells16(c1, c2, n);
        __m512 fx = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(ex, zero, _CMP_LT_OQ), ex, zero);
        __m512 fy = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(ey, zero, _CMP_LT_OQ), ey, zero);
        const __m512 sum = _mm512_add_ps(fx, fy);
        const __mmask16 past = _mm512_cmp_ps_mask(sum, one, _CMP_GT_OQ);
        const __mmask16 upper = past & room, rescale = past & ~upper;
        if (rescale) {  // rare: only on the far edge's cells
            const __m512 inv = _mm512_div_ps(one, sum);
            fx = _mm512_mask_mul_ps(fx, rescale, fx, inv);
            fy = _mm512_mask_mul_ps(fy, rescale, fy, inv);
        }
        _mm512_store_ps(weight[0], _mm512_mask_blend_ps(upper, _mm512_sub_ps(_mm512_sub_ps(one, fx), fy),
                                                         _mm512_sub_ps(_mm512_add_ps(fx, fy), one)));
        _mm512_store_ps(weight[1], _mm512_mask_blend_ps(upper, fx, _mm512_sub_ps(one, fx)));
        _mm512_store_ps(weight[2], _mm512_mask_blend_ps(upper, fy, _mm512_sub_ps(one, fy)));
        // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i (uint32).
        const __m512i one_i = _mm512_set1_epi32(1);
        const __m512i np1 = _mm512_add_epi32(n, one_i);
        const __m512i tri_i = _mm512_srli_epi32(_mm512_mullo_epi32(i, _mm512_sub_epi32(i, one_i)), 1);
        const __m512i row_i = _mm512_sub_epi32(_mm512_mullo_epi32(i, np1), tri_i);
        const __m512i row_next = _mm512_add_epi32(row_i, _mm512_sub_epi32(np1, i));
        const __m512i right = _mm512_add_epi32(row_next, j), up = _mm512_add_epi32(_mm512_add_epi32(row_i, j), one_i);
        const __m512i e0 = _mm512_mask_blend_epi32(upper, _mm512_add_epi32(row_i, j), _mm512_add_epi32(right, one_i));
        const __m512i e1 = _mm512_mask_blend_epi32(upper, right, up);
        const __m512i e2 = _mm512_mask_blend_epi32(upper, up, right);
        const __m512i three = _mm512_set1_epi32(3);
        const __m512i e[3] = {e0, e1, e2};
        for (int c = 0; c < 3; ++c)
            _mm512_store_si512(point[c], _mm512_mullo_epi32(_mm512_add_epi32(first, e[c]), three));
        // One cell: one triangle, one side, and the same cell and sub-triangle in every lane.
        const __m512i lane0 = _mm512_set1_epi32(k0);
        auto uniform = [&](__m512i v) {
            return _mm512_mask_cmpeq_epi32_mask(hm, v, _mm512_permutexvar_epi32(lane0, v)) == hm;
        };
        auto all_or_none = [&](__mmask16 m) { return (m & hm) == ((m >> k0 & 1) ? hm : 0); };
        one_cell = one_triangle && uniform(i) && uniform(j) && all_or_none(upper) && all_or_none(front_lanes);
        if (one_cell) {
            const float* E = &((front_lanes >> k0 & 1) ? b.front : b.back)->x;
            for (int c = 0; c < 3; ++c) __builtin_prefetch(E + point[c][k0]);
            return;
        }
        for (int k = 0; k < 16; ++k)
            if (hm >> k & 1) {
                const float* E = &((front_lanes >> k & 1) ? b.front : b.back)->x;
                __builtin_prefetch(E + point[0][k]);
                __builtin_prefetch(E + point[1][k]);
                __builtin_prefetch(E + point[2][k]);
            }
    }

    // The common packet in one step instead of locate16 and blend16: all 16 lanes hit one
    // triangle, from one side, inside it (Embree's barycentrics need no clamp) and in at most
    // ten sub-triangles of the lattice's cells (nearly always one, or two across a cell's edge
    // or diagonal, as a row of pixels crosses the lattice along a line; more in a distant
    // view). On a sub-triangle the light is an affine function of the cell coordinates: its
    // three corners read once (scalar loads, no gathers) and two fused multiply-adds per
    // channel and lane, E = c0 + fx (c1 - c0) + fy (c2 - c0) (lower; upper: (c1 + c2 - c0) +
    // fx (c0 - c1) + fy (c0 - c2)), which is lattice_lerp's E0 w0 + E1 w1 + E2 w2 to float
    // rounding. The albedo only with_albedo (a painting's is its texture). Returns false,
    // having written nothing, for any other packet (the caller then takes locate16 and
    // blend16).
    bool light16_cells(const BakedLattice& b, const RTCHit16& h, const std::int32_t* __restrict back,
                       bool with_albedo, LaneLight& __restrict out) {
        const unsigned g0 = h.geomID[0], p0 = h.primID[0];
        const __m512i prim = _mm512_loadu_si512(h.primID);
        if (_mm512_cmpneq_epi32_mask(prim, _mm512_set1_epi32(int(p0)))) return false;
        TriangleCache& c = triangle_cache_;
        if (g0 != c.geom || p0 != c.prim) {  // another triangle: its data
            c.geom = g0, c.prim = p0;
            c.t = std::uint64_t(b.first_triangle[g0]) + p0;
            c.w = b.normal[c.t];
            c.n = std::int32_t(b.segments[c.t]);
            c.front_points = b.front + b.offset[c.t], c.back_points = b.back + b.offset[c.t];
            c.albedo = b.albedo[c.t], c.emission = b.emission[c.t];
        }
        // One triangle: Embree's normal is the same in every lane (lane 0's, w . Ng as locate16's).
        const bool normals_agree = c.w.x * h.Ng_x[0] + c.w.y * h.Ng_y[0] + c.w.z * h.Ng_z[0] > 0;
        const __m512i back_i = _mm512_loadu_si512(back);
        const __mmask16 front = __mmask16(normals_agree ? 0xFFFF : 0) ^ _mm512_test_epi32_mask(back_i, back_i);
        if (front != 0 && front != 0xFFFF) return false;
        const __m512 b1 = _mm512_loadu_ps(h.u), b2 = _mm512_loadu_ps(h.v);
        const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
        // Inside: b1, b2 >= 0 and b1 + b2 <= 1 (false for NaN), so lattice_cell's clamps and
        // its scaling back onto the far edge change nothing.
        const __mmask16 inside = _mm512_cmp_ps_mask(b1, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(b2, zero, _CMP_GE_OQ) &
                                 _mm512_cmp_ps_mask(_mm512_add_ps(b1, b2), one, _CMP_LE_OQ);
        if (inside != 0xFFFF) return false;
        // Inside, no lane's position in its cell is negative: locate16's clamp is not needed.
        const auto [i, j, fx, fy, room] = cells16(b1, b2, _mm512_set1_epi32(c.n));
        const __mmask16 past = _mm512_cmp_ps_mask(_mm512_add_ps(fx, fy), one, _CMP_GT_OQ);
        const __mmask16 upper = past & room;
        if (past & ~room) return false;  // on the far edge: lattice_cell scales back onto it
        const bool seen_front = front != 0;
        // The sub-triangle of a lane and the lanes on it.
        auto sub_triangle = [&](int lane, __mmask16& lanes) -> const CellLight& {
            const __m512i at = _mm512_set1_epi32(lane);
            const std::int32_t ci = _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(at, i)));
            const std::int32_t cj = _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(at, j)));
            const bool up = (upper >> lane) & 1;
            lanes = _mm512_cmpeq_epi32_mask(i, _mm512_set1_epi32(ci)) & _mm512_cmpeq_epi32_mask(j, _mm512_set1_epi32(cj)) &
                    (up ? upper : __mmask16(~upper));
            return cell_light(ci, cj, up, seen_front);
        };
        // Lane 0's sub-triangle, then lane 15's, then the first lane left out's in turn (a
        // distant view's pixels lie far apart on the lattice), up to kMaxCells. Each costs a
        // few vector operations; locate16 and blend16 cost 9 to 18 gathers.
        constexpr int kMaxCells = 10;
        __mmask16 covered;
        const CellLight& first = sub_triangle(0, covered);
        __m512 E[3];
        for (int k = 0; k < 3; ++k) E[k] = first.light(k, fx, fy);
        // The lanes not yet covered that lie on lane's sub-triangle, lit from it.
        auto add_cell = [&](int lane) {
            __mmask16 lanes;
            const CellLight& cell = sub_triangle(lane, lanes);
            lanes &= __mmask16(~covered);
            for (int k = 0; k < 3; ++k) E[k] = _mm512_mask_blend_ps(lanes, E[k], cell.light(k, fx, fy));
            covered |= lanes;
        };
        // A straight row crosses each cell once, so a packet's cells are runs of lanes and lane
        // 15's is the other of two. Its lookup does not wait for lane 0's lanes, as the loop's
        // next lane would.
        if (covered != 0xFFFF) add_cell(15);
        for (int cells = 2; covered != 0xFFFF; ++cells) {
            if (cells == kMaxCells) return false;
            add_cell(std::countr_zero(unsigned(__mmask16(~covered))));
        }
        for (int k = 0; k < 3; ++k) _mm512_store_ps(out.E[k], E[k]);
        const Vec3f em = seen_front ? c.emission : Vec3f{0.0f, 0.0f, 0.0f};
        if (with_albedo) {
            _mm512_store_ps(out.a[0], _mm512_set1_ps(c.albedo.x)), _mm512_store_ps(out.a[1], _mm512_set1_ps(c.albedo.y));
            _mm512_store_ps(out.a[2], _mm512_set1_ps(c.albedo.z));
        }
        _mm512_store_ps(out.M[0], _mm512_set1_ps(em.x)), _mm512_store_ps(out.M[1], _mm512_set1_ps(em.y));
        _mm512_store_ps(out.M[2], _mm512_set1_ps(em.z));
        return true;
    }
    // A sub-triangle's light as E = base + fx dx + fy dy, per channel (the coefficients as
    // floats: the multiply-adds take them as broadcast memory operands).
    struct CellLight {
        // Triangle t, cell (i, j), sub-triangle and side in one word: t < 2^30, and
        // 0 <= i, j < n < 2^16 (lanes16 keeps the points, about n^2 / 2 a triangle, below
        // 2^31 / 3).
        static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
        static std::uint64_t key_of(std::uint64_t t, std::int32_t i, std::int32_t j, bool upper, bool front) {
            return t << 34 | std::uint64_t(std::uint32_t(i)) << 18 | std::uint64_t(std::uint32_t(j)) << 2 |
                   std::uint64_t(upper) << 1 | std::uint64_t(front);
        }
        std::uint64_t key = kEmpty;
        float base[3], dx[3], dy[3];
        // Channel k's light in 16 lanes at cell coordinates (fx, fy).
        __m512 light(int k, __m512 fx, __m512 fy) const {
            return _mm512_fmadd_ps(fy, _mm512_set1_ps(dy[k]), _mm512_fmadd_ps(fx, _mm512_set1_ps(dx[k]), _mm512_set1_ps(base[k])));
        }
    };
    // The last packets' triangle (consecutive packets of a row nearly always share it).
    struct TriangleCache {
        unsigned geom = RTC_INVALID_GEOMETRY_ID, prim = 0;
        std::uint64_t t = 0;
        Vec3f w;  // the triangle's normal
        std::int32_t n = 0;
        const Vec3f *front_points = nullptr, *back_points = nullptr;
        Vec3f albedo, emission;
    } triangle_cache_;
    // The sub-triangles lit lately, direct-mapped by their cell's low bits (a chunk's rows
    // cross the same cells one after another; two entries missed about once a packet in a
    // distant view).
    static constexpr std::size_t kCellSlots = 64;
    CellLight cells_[kCellSlots];
    // The light of sub-triangle (ci, cj, upper) of the cached triangle's lattice, seen from the
    // front or the back: cached, or made from its corners as locate() finds them (rows i and
    // i + 1 start at row_i, row_next), valid until the next call.
    const CellLight& cell_light(std::int32_t ci, std::int32_t cj, bool upper, bool front) {
        TriangleCache& c = triangle_cache_;
        const std::uint64_t key = CellLight::key_of(c.t, ci, cj, upper, front);
        CellLight* slot = &cells_[(std::uint32_t(ci) & 7) << 3 | (std::uint32_t(cj) & 3) << 1 | std::uint32_t(upper)];
        if (slot->key == key) return *slot;
        CellLight& cl = *slot;
        const std::uint64_t nn = std::uint64_t(c.n), i = std::uint64_t(ci), j = std::uint64_t(cj);
        const std::uint64_t row_i = i * (nn + 1) - i * (i - 1) / 2, row_next = row_i + (nn + 1 - i);
        const std::uint64_t right = row_next + j, up = row_i + j + 1;
        const Vec3f* E = front ? c.front_points : c.back_points;
        const Vec3f c0 = E[upper ? row_next + j + 1 : row_i + j];
        const Vec3f c1 = E[upper ? up : right], c2 = E[upper ? right : up];
        auto channel = [&](int k, float a0, float a1, float a2) {
            cl.base[k] = upper ? a1 + a2 - a0 : a0;
            cl.dx[k] = upper ? a0 - a1 : a1 - a0;
            cl.dy[k] = upper ? a0 - a2 : a2 - a0;
        };
        channel(0, c0.x, c1.x, c2.x), channel(1, c0.y, c1.y, c2.y), channel(2, c0.z, c1.z, c2.z);
        cl.key = key;
        return cl;
    }

    void blend16(const BakedLattice& b, LaneLight& __restrict out) const {
        const __mmask16 on_front = hit_lanes & front_lanes, on_back = hit_lanes & ~front_lanes;
        const float *F = &b.front->x, *B = &b.back->x;
        const int k0 = first_lane;
        auto corner = [&](int c, int axis) {
            if (one_cell)
                return _mm512_set1_ps(((front_lanes >> k0 & 1) ? F : B)[point[c][k0] + axis]);
            const __m512i at = _mm512_add_epi32(_mm512_load_si512(point[c]), _mm512_set1_epi32(axis));
            __m512 v = _mm512_setzero_ps();
            if (on_front) v = _mm512_mask_i32gather_ps(v, on_front, at, F, 4);
            if (on_back) v = _mm512_mask_i32gather_ps(v, on_back, at, B, 4);
            return v;
        };
        const __m512 w0 = _mm512_load_ps(weight[0]), w1 = _mm512_load_ps(weight[1]), w2 = _mm512_load_ps(weight[2]);
        float* E[3] = {out.E[0], out.E[1], out.E[2]};
        for (int axis = 0; axis < 3; ++axis)
            _mm512_store_ps(E[axis], _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(corner(0, axis), w0),
                                                                 _mm512_mul_ps(corner(1, axis), w1)),
                                                   _mm512_mul_ps(corner(2, axis), w2)));
        const float *albedo = &b.albedo->x, *emission = &b.emission->x;
        float* A[3] = {out.a[0], out.a[1], out.a[2]};
        float* M[3] = {out.M[0], out.M[1], out.M[2]};
        if (one_triangle) {
            const std::size_t t0 = 3 * std::size_t(tri[k0]);
            for (int axis = 0; axis < 3; ++axis) {
                _mm512_store_ps(A[axis], _mm512_set1_ps(albedo[t0 + axis]));
                _mm512_store_ps(M[axis], _mm512_maskz_mov_ps(on_front, _mm512_set1_ps(emission[t0 + axis])));
            }
            return;
        }
        const __m512i t3 = _mm512_mullo_epi32(_mm512_load_si512(tri), _mm512_set1_epi32(3));
        for (int axis = 0; axis < 3; ++axis) {
            const __m512i at = _mm512_add_epi32(t3, _mm512_set1_epi32(axis));
            _mm512_store_ps(A[axis], _mm512_mask_i32gather_ps(_mm512_setzero_ps(), hit_lanes, at, albedo, 4));
            _mm512_store_ps(M[axis], _mm512_mask_i32gather_ps(_mm512_setzero_ps(), on_front, at, emission, 4));
        }
    }
#pragma GCC diagnostic pop
#endif
};

}  // namespace display
}  // namespace gigascroll

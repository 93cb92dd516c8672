// The "light" step of the display pass on a baked lattice (display/baked_lattice.h): a
// packet's 16 lanes lit from the lattice points around each lane's hit, W lanes at a time
// (common/lanes.h: one text for every width, the same floats at each).
#pragma once
#include <embree3/rtcore.h>

#include <bit>
#include <cstdint>

#include "common/lanes.h"
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
    template <int W = kWidest>
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
        // The cells in lanes (lattice_cell_lanes: lattice_cell's operations).
        using L = Lanes<W>;
        for (int k0 = 0; k0 < 16; k0 += W) {
            const LatticeCellLanes<W> c = lattice_cell_lanes<W>(L::I::load(segments + k0), L::F::load(b1 + k0),
                                                                L::F::load(b2 + k0));
            c.i.store(cell_i + k0), c.j.store(cell_j + k0);
            L::select(c.upper, typename L::I(1), typename L::I(0)).store(upper_of + k0);
            c.w0.store(weight[0] + k0), c.w1.store(weight[1] + k0), c.w2.store(weight[2] + k0);
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

// GCC 12 warns that the _mm512_undefined_* sources inside its own AVX-512 intrinsics may be
// used uninitialized (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
    // locate() and blend() on vectors: the arrays gathered with 32-bit float indices (the
    // caller checks lanes16(): 3 x the triangles and the points below 2^31), the cell
    // arithmetic lattice_cell_lanes, the corners' indices in uint32 (n < 2^16, so i (n + 1)
    // and a triangle's (n + 1)(n + 2) / 2 points fit). The same operations in the same order
    // as locate's, hence the same floats; lanes without a hit are masked out of the gathers
    // (their values are never read).
    alignas(64) std::int32_t point[3][16];  // float index of each corner in front or back
    unsigned hit_lanes = 0, front_lanes = 0;  // lane k in bit k
    int first_lane = 0;  // the first hit lane
    bool one_triangle = false, one_cell = false;  // under every hit lane

    static bool lanes16(const BakedLattice& b) {
        constexpr std::uint64_t kLimit = (std::uint64_t(1) << 31) / 3;
        return b.triangles > 0 && b.triangles < kLimit && b.points < kLimit;
    }

    // lattice_cell's cell in lanes, of clamped barycentrics (c1, c2) on triangles of n
    // segments a side: the cell (i, j), the position in it (x, y, before the clamp at 0), and
    // room: whether the cell has an upper sub-triangle (i + j + 2 <= n). light16_cells'
    // part of lattice_cell_lanes (its barycentrics need no clamp).
    template <int W>
    struct Cells {
        typename Lanes<W>::I i, j;
        typename Lanes<W>::F x, y;
        typename Lanes<W>::M room;
    };
    template <int W>
    static Cells<W> cells(typename Lanes<W>::F c1, typename Lanes<W>::F c2, typename Lanes<W>::I n) {
        using L = Lanes<W>;
        using I = typename L::I;
        const I n1 = n - I(1);
        const typename L::F nf = L::to_float(n);
        const typename L::F x = c1 * nf, y = c2 * nf;
        Cells<W> c;
        c.i = min(to_int(x), n1);
        c.j = min(to_int(y), n1 - c.i);
        c.x = x - L::to_float(c.i), c.y = y - L::to_float(c.j);
        c.room = c.i + c.j + I(2) <= n;
        return c;
    }

    // The packet's triangle data in W lanes from k0: broadcast when one triangle lies under
    // every hit lane (nearly every packet; on these cores a 16-lane gather costs about as
    // much as 16 loads), else gathered.
    template <int W>
    struct TriangleLanes {
        typename Lanes<W>::I t, n, first;
        typename Lanes<W>::F wx, wy, wz;
    };
    template <int W>
    TriangleLanes<W> triangle_lanes(const BakedLattice& b, const RTCHit16& h, typename Lanes<W>::M hm, int k0) const {
        using L = Lanes<W>;
        using I = typename L::I;
        using F = typename L::F;
        TriangleLanes<W> r;
        if (one_triangle) {
            const std::uint32_t t0 = tri[first_lane];
            const Vec3f w = b.normal[t0];
            r.t = I(std::int32_t(t0));
            r.wx = F(w.x), r.wy = F(w.y), r.wz = F(w.z);
            r.n = I(std::int32_t(b.segments[t0]));
            r.first = I(std::int32_t(std::uint32_t(b.offset[t0])));
            return r;
        }
        const auto all = mask_of<W>(~0u);
        const I g = L::select(hm, I::load(h.geomID + k0), I(0)), p = L::select(hm, I::load(h.primID + k0), I(0));
        r.t = gather(I(0), b.first_triangle, g, all) + p;
        const I t3 = r.t * I(3);
        r.wx = gather(F(0.0f), b.normal, t3, all);
        r.wy = gather(F(0.0f), b.normal, t3 + I(1), all);
        r.wz = gather(F(0.0f), b.normal, t3 + I(2), all);
        r.n = gather(I(0), b.segments, r.t, all);
        // The triangle's first point: the low word of offset[t] (below 2^31 / 3).
        r.first = gather(I(0), b.offset, r.t + r.t, all);
        return r;
    }

    // Whether one triangle lies under every hit lane (hit lanes in hm, the first k0).
    template <int W>
    static bool under_one_triangle(const RTCHit16& h, unsigned hm, int k0) {
        using I = typename Lanes<W>::I;
        const I g0(std::int32_t(h.geomID[k0])), p0(std::int32_t(h.primID[k0]));
        bool one = true;
        for (int k = 0; k < 16; k += W)
            one = one && !any<W>(mask_of<W>(hm >> k) & ((I::load(h.geomID + k) != g0) | (I::load(h.primID + k) != p0)));
        return one;
    }

    template <int W = kWidest>
    void locate16(const BakedLattice& b, const RTCHit16& h, const int* __restrict hit,
                  const std::int32_t* __restrict back) {
        using L = Lanes<W>;
        using I = typename L::I;
        using F = typename L::F;
        unsigned hm = 0;
        for (int k = 0; k < 16; k += W) hm |= nonzero(I::load(hit + k)).bits() << k;
        hit_lanes = hm;
        const int k0 = std::countr_zero(hm);  // the caller has hits
        first_lane = k0;
        one_triangle = under_one_triangle<W>(h, hm, k0);
        if (one_triangle) tri[k0] = b.first_triangle[h.geomID[k0]] + h.primID[k0];
        alignas(64) std::int32_t ci[16], cj[16];
        unsigned upper_lanes = 0;
        front_lanes = 0;
        for (int k = 0; k < 16; k += W) {
            const auto hmk = mask_of<W>(hm >> k);
            const TriangleLanes<W> tl = triangle_lanes<W>(b, h, hmk, k);
            tl.t.store(tri + k);
            const F facing = tl.wx * F::load(h.Ng_x + k) + tl.wy * F::load(h.Ng_y + k) + tl.wz * F::load(h.Ng_z + k);
            front_lanes |= ((facing > F(0.0f)) ^ nonzero(I::load(back + k))).bits() << k;
            const F c1 = L::select(hmk, F::load(h.u + k), F(0.0f)), c2 = L::select(hmk, F::load(h.v + k), F(0.0f));
            const LatticeCellLanes<W> c = lattice_cell_lanes<W>(tl.n, c1, c2);
            c.w0.store(weight[0] + k), c.w1.store(weight[1] + k), c.w2.store(weight[2] + k);
            c.i.store(ci + k), c.j.store(cj + k);
            upper_lanes |= c.upper.bits() << k;
            // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i (uint32).
            const I np1 = tl.n + I(1);
            const I row_i = c.i * np1 - srl(c.i * (c.i - I(1)), 1);
            const I row_next = row_i + (np1 - c.i);
            const I right = row_next + c.j, up = row_i + c.j + I(1);
            const I e[3] = {L::select(c.upper, right + I(1), row_i + c.j), L::select(c.upper, up, right),
                            L::select(c.upper, right, up)};
            for (int q = 0; q < 3; ++q) ((tl.first + e[q]) * I(3)).store(point[q] + k);
        }
        // One cell: one triangle, one side, and the same cell and sub-triangle in every lane.
        auto all_or_none = [&](unsigned m) { return (m & hm) == ((m >> k0 & 1) ? hm : 0u); };
        one_cell = one_triangle && all_or_none(upper_lanes) && all_or_none(front_lanes);
        for (int k = 0; k < 16 && one_cell; k += W)
            one_cell = !any<W>(mask_of<W>(hm >> k) & ((I::load(ci + k) != I(ci[k0])) | (I::load(cj + k) != I(cj[k0]))));
        prefetch_corners(b);
    }

    // The hit lanes' corners fetched (one cell: its three).
    void prefetch_corners(const BakedLattice& b) const {
        const int k0 = first_lane;
        if (one_cell) {
            const float* E = &((front_lanes >> k0 & 1) ? b.front : b.back)->x;
            for (int c = 0; c < 3; ++c) __builtin_prefetch(E + point[c][k0]);
            return;
        }
        for (int k = 0; k < 16; ++k)
            if (hit_lanes >> k & 1) {
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
    template <int W = kWidest>
    bool light16_cells(const BakedLattice& b, const RTCHit16& h, const std::int32_t* __restrict back,
                       bool with_albedo, LaneLight& __restrict out) {
        using L = Lanes<W>;
        using I = typename L::I;
        using F = typename L::F;
        constexpr int kChunks = 16 / W;
        const unsigned g0 = h.geomID[0], p0 = h.primID[0];
        for (int k = 0; k < 16; k += W)
            if (any<W>(I::load(h.primID + k) != I(std::int32_t(p0)))) return false;
        const TriangleCache& c = cached_triangle(b, g0, p0);
        // One triangle: Embree's normal is the same in every lane (lane 0's, w . Ng as locate16's).
        const bool normals_agree = c.w.x * h.Ng_x[0] + c.w.y * h.Ng_y[0] + c.w.z * h.Ng_z[0] > 0;
        unsigned back_lanes = 0;
        for (int k = 0; k < 16; k += W) back_lanes |= nonzero(I::load(back + k)).bits() << k;
        const unsigned front = (normals_agree ? 0xFFFFu : 0u) ^ back_lanes;
        if (front != 0 && front != 0xFFFF) return false;
        // Per lane its cell (ci, cj), sub-triangle (upper) and position in the cell (fx, fy).
        I ci_v[kChunks], cj_v[kChunks];
        F fx[kChunks], fy[kChunks];
        unsigned upper = 0;
        typename L::M upper_m[kChunks];
        for (int q = 0; q < kChunks; ++q) {
            const F b1 = F::load(h.u + q * W), b2 = F::load(h.v + q * W);
            // Inside: b1, b2 >= 0 and b1 + b2 <= 1 (false for NaN), so lattice_cell's clamps and
            // its scaling back onto the far edge change nothing.
            if (!all<W>((b1 >= F(0.0f)) & (b2 >= F(0.0f)) & (b1 + b2 <= F(1.0f)))) return false;
            // Inside, no lane's position in its cell is negative: locate16's clamp is not needed.
            const Cells<W> cl = cells<W>(b1, b2, I(c.n));
            const auto past = cl.x + cl.y > F(1.0f);
            if (any<W>(past & !cl.room)) return false;  // on the far edge: lattice_cell scales back onto it
            upper_m[q] = past & cl.room;
            upper |= upper_m[q].bits() << (q * W);
            ci_v[q] = cl.i, cj_v[q] = cl.j, fx[q] = cl.x, fy[q] = cl.y;
        }
        const bool seen_front = front != 0;
        // Lane 0's sub-triangle, then lane 15's, then the first lane left out's in turn (a
        // distant view's pixels lie far apart on the lattice), up to kMaxCells. Each costs a
        // few vector operations; locate16 and blend16 cost 9 to 18 gathers. A straight row
        // crosses each cell once, so a packet's cells are runs of lanes and lane 15's is the
        // other of two. Its lookup does not wait for lane 0's lanes, as the loop's next lane
        // would.
        constexpr int kMaxCells = 10;
        F E[3][kChunks];
        typename L::M covered[kChunks];
        auto covered_bits = [&] {
            unsigned bits = 0;
            for (int q = 0; q < kChunks; ++q) bits |= covered[q].bits() << (q * W);
            return bits;
        };
        // The lanes not yet covered on lane's sub-triangle, lit from it (the first: every
        // lane lit, the others' light replaced later).
        auto add_cell = [&](int lane, bool first) {
            const std::int32_t li = lane_value(ci_v[lane / W], lane % W), lj = lane_value(cj_v[lane / W], lane % W);
            const bool up = (upper >> lane) & 1;
            const CellLight& cell = cell_light(li, lj, up, seen_front);
            for (int q = 0; q < kChunks; ++q) {
                auto on = (ci_v[q] == I(li)) & (cj_v[q] == I(lj)) & (up ? upper_m[q] : !upper_m[q]);
                if (!first) on = on & !covered[q];
                for (int k = 0; k < 3; ++k) {
                    const F lit = cell.template light<W>(k, fx[q], fy[q]);
                    E[k][q] = first ? lit : L::select(on, lit, E[k][q]);
                }
                covered[q] = first ? on : covered[q] | on;
            }
        };
        add_cell(0, true);
        if (covered_bits() != 0xFFFF) add_cell(15, false);
        for (int cells_lit = 2; covered_bits() != 0xFFFF; ++cells_lit) {
            if (cells_lit == kMaxCells) return false;
            add_cell(std::countr_zero(~covered_bits()), false);
        }
        for (int k = 0; k < 3; ++k)
            for (int q = 0; q < kChunks; ++q) E[k][q].store(out.E[k] + q * W);
        const Vec3f em = seen_front ? c.emission : Vec3f{0.0f, 0.0f, 0.0f};
        for (int q = 0; q < kChunks; ++q) {
            if (with_albedo)
                F(c.albedo.x).store(out.a[0] + q * W), F(c.albedo.y).store(out.a[1] + q * W),
                    F(c.albedo.z).store(out.a[2] + q * W);
            F(em.x).store(out.M[0] + q * W), F(em.y).store(out.M[1] + q * W), F(em.z).store(out.M[2] + q * W);
        }
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
        // Channel k's light in W lanes at cell coordinates (fx, fy).
        template <int W>
        typename Lanes<W>::F light(int k, typename Lanes<W>::F fx, typename Lanes<W>::F fy) const {
            using F = typename Lanes<W>::F;
            return fma(fy, F(dy[k]), fma(fx, F(dx[k]), F(base[k])));
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
    const TriangleCache& cached_triangle(const BakedLattice& b, unsigned g0, unsigned p0) {
        TriangleCache& c = triangle_cache_;
        if (g0 != c.geom || p0 != c.prim) {  // another triangle: its data
            c.geom = g0, c.prim = p0;
            c.t = std::uint64_t(b.first_triangle[g0]) + p0;
            c.w = b.normal[c.t];
            c.n = std::int32_t(b.segments[c.t]);
            c.front_points = b.front + b.offset[c.t], c.back_points = b.back + b.offset[c.t];
            c.albedo = b.albedo[c.t], c.emission = b.emission[c.t];
        }
        return c;
    }
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

    // blend() after locate16, on vectors: one cell's corners broadcast, else gathered from the
    // front or the back points per lane; the albedo and the emission broadcast for one
    // triangle, else gathered.
    template <int W = kWidest>
    void blend16(const BakedLattice& b, LaneLight& __restrict out) const {
        using L = Lanes<W>;
        using F = typename L::F;
        using I = typename L::I;
        const int k0 = first_lane;
        const float* one_cell_points = &((front_lanes >> k0 & 1) ? b.front : b.back)->x;
        for (int k = 0; k < 16; k += W) {
            const auto hit = mask_of<W>(hit_lanes >> k), front = mask_of<W>(front_lanes >> k);
            const auto on_front = hit & front, on_back = hit & !front;
            auto corner = [&](int c, int axis) {
                if (one_cell) return F(one_cell_points[point[c][k0] + axis]);
                const I at = I::load(point[c] + k) + I(axis);
                F v(0.0f);
                if (any<W>(on_front)) v = gather(v, b.front, at, on_front);
                if (any<W>(on_back)) v = gather(v, b.back, at, on_back);
                return v;
            };
            const F w0 = F::load(weight[0] + k), w1 = F::load(weight[1] + k), w2 = F::load(weight[2] + k);
            for (int axis = 0; axis < 3; ++axis)
                (corner(0, axis) * w0 + corner(1, axis) * w1 + corner(2, axis) * w2).store(out.E[axis] + k);
            const float *albedo = &b.albedo->x, *emission = &b.emission->x;
            if (one_triangle) {
                const std::size_t t0 = 3 * std::size_t(tri[k0]);
                for (int axis = 0; axis < 3; ++axis) {
                    F(albedo[t0 + axis]).store(out.a[axis] + k);
                    L::select(on_front, F(emission[t0 + axis]), F(0.0f)).store(out.M[axis] + k);
                }
                continue;
            }
            const I t3 = I::load(tri + k) * I(3);
            for (int axis = 0; axis < 3; ++axis) {
                const I at = t3 + I(axis);
                gather(F(0.0f), b.albedo, at, hit).store(out.a[axis] + k);
                gather(F(0.0f), b.emission, at, on_front).store(out.M[axis] + k);
            }
        }
    }
#pragma GCC diagnostic pop
};

}  // namespace display
}  // namespace gigascroll

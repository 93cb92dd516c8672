#include "photon/adaptive_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.h"
#include "photon/gather.h"

namespace gigascroll {

namespace {
constexpr float kMinCellsPerRadius = 0.25f;

// Cells per radius for a query expected to find `found` photons. A row of cells costs about
// as much as testing a few dozen photons (its prefix-sum loads and the chord's sqrt), so
// sparse photons want cells wider than the radius and only thousands found pay for finer
// ones (measured with bench_photon's BM_AdaptiveCells on the Cornell box and the office).
float cells_for_density(double found) {
    if (found < 8) return 0.25f;
    if (found < 60) return 0.5f;
    if (found < 1000) return 1.0f;
    if (found < 4000) return 2.0f;
    return 3.0f;
}

// The cell coordinate of u (cell units), clamped to [-1, g] so it converts safely.
std::int64_t cell_floor(float u, std::int64_t g) {
    return std::int64_t(std::clamp(std::floor(u), -1.0f, float(g)));
}
}  // namespace

AdaptiveGrid::AdaptiveGrid(const std::vector<Photon>& photons, float radius, float cells_per_radius,
                           AdaptiveGrid* recycle, unsigned threads)
    : r_(radius) {
    if (recycle) {
        start_ = std::move(recycle->start_), photons_ = std::move(recycle->photons_);
        for (auto [to, from] : {std::pair{&px_, &recycle->px_}, {&py_, &recycle->py_}, {&pz_, &recycle->pz_},
                                {&nx_, &recycle->nx_}, {&ny_, &recycle->ny_}, {&nz_, &recycle->nz_},
                                {&pr_, &recycle->pr_}, {&pg_, &recycle->pg_}, {&pb_, &recycle->pb_}})
            *to = std::move(*from);
        // Their contents are stale until build() overwrites every element (a resize within
        // the old size initialises nothing).
    }
    require(std::isfinite(radius) && radius > 0.0f, "AdaptiveGrid: radius must be positive and finite");
    require(cells_per_radius == 0 || (cells_per_radius >= kMinCellsPerRadius && cells_per_radius <= kMaxCellsPerRadius),
            "AdaptiveGrid: cells_per_radius must be 0 (automatic) or within [0.25, 4]");
    require(photons.size() < std::numeric_limits<std::uint32_t>::max(), "AdaptiveGrid: too many photons");
    lo_ = hi_ = {0, 0, 0};
    if (!photons.empty()) {
        lo_ = hi_ = photons[0].p;
        for (const Photon& p : photons) {
            lo_ = vmin(lo_, p.p);
            hi_ = vmax(hi_, p.p);
        }
    }
    // Within 1e30 the cell arithmetic below (extent / edge, doubling edges) cannot overflow.
    for (int a = 0; a < 3; ++a)
        require(std::abs(lo_[a]) <= 1e30f && std::abs(hi_[a]) <= 1e30f,
                "AdaptiveGrid: photon positions must be finite and within 1e30");
    if (cells_per_radius == 0) {
        // Seed-sized cells (or coarser if they would be many) first, of the positions alone
        // (a sixth of the photons' bytes); the photons found around a sample of photons
        // decide the edge of the grid then built.
        build(photons, radius, true, threads);
        const std::size_t n = photons.size(), samples = std::min<std::size_t>(n, 256);
        double found = 0;
        for (std::size_t i = 0; i < samples; ++i) found += double(count_in_radius(photons[i * n / samples].p, radius * radius));
        const float k = cells_for_density(samples ? found / double(samples) : 0.0);
        build(photons, radius / k, false, threads);
    } else {
        build(photons, radius / cells_per_radius, false, threads);
    }
}

std::uint64_t AdaptiveGrid::cells_for(float edge) const {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::floor(double(hi_[a] - lo_[a]) / double(edge) + 1e-3) + 2.0;
    return cells > 1e18 ? std::numeric_limits<std::uint64_t>::max() : std::uint64_t(cells);
}

void AdaptiveGrid::build(const std::vector<Photon>& photons, float edge, bool positions_only, unsigned threads) {
    const std::size_t n = photons.size();
    // Coarser cells when the table would be large, or when a scene far from the origin makes
    // the rounding of cell coordinates (pad_) a sizeable part of a cell.
    float extent = 0;
    for (int a = 0; a < 3; ++a) extent = std::max({extent, std::abs(lo_[a]), std::abs(hi_[a])});
    extent += edge;
    // Few photons need few cells (a progressive pass rebuilds the grid for a few thousand).
    const double limit = std::max<double>(double(1 << 16), 4.0 * double(n));
    while (double(cells_for(edge)) > limit || 1e-6f * (extent + edge) / edge > 0.2f) edge *= 2.0f;
    h_ = edge;
    inv_h_ = 1.0f / edge;
    origin_ = lo_ - Vec3f(1, 1, 1) * (edge * 0.5f);
    for (int a = 0; a < 3; ++a) {
        const float u = std::floor((hi_[a] - origin_[a]) * inv_h_);
        g_[a] = std::int64_t(u) + 1;
        GS_CHECK(g_[a] >= 1);
    }
    // More than the float rounding of (p - origin) / h, in cell units (at most 0.25 by the
    // loop above): the culling stays conservative for any scene offset.
    pad_ = 1e-3f + 1e-6f * (extent + edge) * inv_h_;

    const std::uint64_t cells = std::uint64_t(g_[0]) * std::uint64_t(g_[1]) * std::uint64_t(g_[2]);
    std::vector<std::uint64_t> key(n);
    const unsigned parts = threads == 0 ? default_threads() : threads;
    parallel_for(n, std::size_t(1) << 15, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            std::int64_t c[3];
            for (int a = 0; a < 3; ++a)
                c[a] = std::clamp<std::int64_t>(cell_floor((photons[i].p[a] - origin_[a]) * inv_h_, g_[a]), 0,
                                                g_[a] - 1);
            key[i] = std::uint64_t((c[2] * g_[1] + c[1]) * g_[0] + c[0]);
        }
    }, parts);
    if (!positions_only) {
        sort_photons_by_key(photons, key, cells, start_, photons_, {&px_, &py_, &pz_, &nx_, &ny_, &nz_, &pr_, &pg_, &pb_},
                            parts);
        return;
    }
    // The same counting sort, positions only (enough for count_in_radius).
    px_.resize(n), py_.resize(n), pz_.resize(n);
    float* x = px_.data(); float* y = py_.data(); float* z = pz_.data();
    counting_sort(key, cells, start_, parts, [&](std::size_t i, std::uint32_t j) {
        x[j] = photons[i].p.x, y[j] = photons[i].p.y, z[j] = photons[i].p.z;
    });
}

std::uint64_t AdaptiveGrid::count_in_radius(Vec3f q, float r2) const {
    PhotonRun rs[kMaxRuns];
    const int nr = runs(q, std::sqrt(r2), rs);
    const float* px = px_.data(); const float* py = py_.data(); const float* pz = pz_.data();
    std::uint64_t found = 0;
    for (int i = 0; i < nr; ++i)
        for (std::uint64_t j = rs[i].begin; j < rs[i].end; ++j) {
            const float dx = px[j] - q.x, dy = py[j] - q.y, dz = pz[j] - q.z;
            found += (dx * dx + dy * dy + dz * dz <= r2) ? 1 : 0;
        }
    return found;
}

int AdaptiveGrid::runs(Vec3f q, float r, PhotonRun* out) const {
    if (px_.empty() || !(r > 0)) return 0;
    const float ux = (q.x - origin_.x) * inv_h_, uy = (q.y - origin_.y) * inv_h_, uz = (q.z - origin_.z) * inv_h_;
    if (!(std::isfinite(ux) && std::isfinite(uy) && std::isfinite(uz))) return 0;
    // The query radius in cells, padded; never more than the build radius's.
    const float ru = std::min(r, r_) * inv_h_ * (1.0f + 1e-5f) + pad_;
    const float ru2 = ru * ru;
    // Distance (in cells) from u to the cell interval [i, i + 1].
    auto gap = [](float u, std::int64_t i) { return std::max({0.0f, float(i) - u, u - float(i + 1)}); };
    const std::int64_t z0 = std::max<std::int64_t>(cell_floor(uz - ru, g_[2]), 0);
    const std::int64_t z1 = std::min(cell_floor(uz + ru, g_[2]), g_[2] - 1);
    int n = 0;
    for (std::int64_t z = z0; z <= z1; ++z) {
        const float dz = gap(uz, z), rz2 = ru2 - dz * dz;
        if (rz2 < 0) continue;
        const float rz = std::sqrt(rz2);
        const std::int64_t y0 = std::max<std::int64_t>(cell_floor(uy - rz, g_[1]), 0);
        const std::int64_t y1 = std::min(cell_floor(uy + rz, g_[1]), g_[1] - 1);
        for (std::int64_t y = y0; y <= y1; ++y) {
            const float dy = gap(uy, y), ry2 = rz2 - dy * dy;
            if (ry2 < 0) continue;
            const float w = std::sqrt(ry2);  // half the chord through this row
            const std::int64_t x0 = std::max<std::int64_t>(cell_floor(ux - w, g_[0]), 0);
            const std::int64_t x1 = std::min(cell_floor(ux + w, g_[0]), g_[0] - 1);
            if (x0 > x1) continue;
            const std::uint64_t row = std::uint64_t((z * g_[1] + y) * g_[0]);
            const std::uint32_t b = start_[row + std::uint64_t(x0)], e = start_[row + std::uint64_t(x1) + 1];
            if (b < e) {
                GS_CHECK(n < kMaxRuns);
                out[n++] = {b, e};
            }
        }
    }
    return n;
}

template <bool CheckNormal>
Vec3f AdaptiveGrid::sum(Vec3f q, Vec3f nq, float r2, float* count) const {
    PhotonRun rs[kMaxRuns];
    const int nr = runs(q, std::sqrt(r2), rs);
    const float* px = px_.data(); const float* py = py_.data(); const float* pz = pz_.data();
    const float* nx = nx_.data(); const float* ny = ny_.data(); const float* nz = nz_.data();
    const float* pr = pr_.data(); const float* pg = pg_.data(); const float* pb = pb_.data();
    auto weight = [&](std::uint64_t j) {
        const float dx = px[j] - q.x, dy = py[j] - q.y, dz = pz[j] - q.z;
        const float d2 = dx * dx + dy * dy + dz * dz;
        if constexpr (CheckNormal) {
            const float agree = nx[j] * nq.x + ny[j] * nq.y + nz[j] * nq.z;
            return float((d2 <= r2) & (agree > kNormalAgreement));
        } else {
            return float(d2 <= r2);
        }
    };
    return sum_runs(rs, nr, pr, pg, pb, weight, count);
}

namespace {
// SurfaceDisc::sector without its table and branches, so the loop over a run vectorises:
// the octant table [pu][pv][steep] as nibbles of one word.
inline int octant_bits(float u, float v) {
    const unsigned idx = unsigned(u >= 0) * 4 + unsigned(v >= 0) * 2 + unsigned(std::fabs(v) > std::fabs(u));
    return int((0x10672354u >> (4 * idx)) & 0xfu);
}
inline int sector(float u, float v) {
    constexpr float c = 0.92387953f, s = 0.38268343f;  // as SurfaceDisc::sector
    const int k = octant_bits(u, v);
    return 2 * k + int(octant_bits(u * c + v * s, v * c - u * s) == k);
}
}  // namespace

template <bool Clipped, bool StopAtForeign>
Vec3f AdaptiveGrid::disc_sum(const SurfaceDisc& d, float* count, float* foreign) const {
    constexpr int kLanes = 8;
    float sr[kLanes] = {}, sg[kLanes] = {}, sb[kLanes] = {}, sw[kLanes] = {}, sf[kLanes] = {};
    const float r2 = d.r * d.r, reach2 = d.reach2[0], thick = d.thickness;
    PhotonRun rs[kMaxRuns];
    const int nr = runs(d.x, d.r, rs);
    const float* px = px_.data(); const float* py = py_.data(); const float* pz = pz_.data();
    const float* nx = nx_.data(); const float* ny = ny_.data(); const float* nz = nz_.data();
    const float* pr = pr_.data(); const float* pg = pg_.data(); const float* pb = pb_.data();
    // The arithmetic of gather_disc and SurfaceDisc::contains, term for term, so the same
    // photons pass: within r (sphere), then normals, the slab |h| <= thickness, the disc
    // (a clipped one: the reach of the photon's sector).
    auto lane = [&](std::uint64_t j, int l) {
        const float dx = px[j] - d.x.x, dy = py[j] - d.x.y, dz = pz[j] - d.x.z;
        const float d2 = dx * dx + dy * dy + dz * dz;
        const float agree = nx[j] * d.n.x + ny[j] * d.n.y + nz[j] * d.n.z;
        const float h = dx * d.n.x + dy * d.n.y + dz * d.n.z;
        const float u = dx * d.t.x + dy * d.t.y + dz * d.t.z, v = dx * d.b.x + dy * d.b.y + dz * d.b.z;
        const bool near = d2 <= r2;
        float reach = reach2;
        if constexpr (Clipped) reach = d.reach2[sector(u, v)];
        const bool in = (agree > 0.5f) & (std::fabs(h) <= thick) & (u * u + v * v <= reach);
        const float w = float(near & in);
        sr[l] += w * pr[j];
        sg[l] += w * pg[j];
        sb[l] += w * pb[j];
        sw[l] += w;
        sf[l] += float(near & !in);
    };
    for (int i = 0; i < nr; ++i) {
        std::uint64_t j = rs[i].begin;
        for (; j + kLanes <= rs[i].end; j += kLanes)
            for (int l = 0; l < kLanes; ++l) lane(j + std::uint64_t(l), l);
        for (int l = 0; j < rs[i].end; ++j, ++l) lane(j, l);
        if constexpr (StopAtForeign) {
            float any = 0;
            for (int l = 0; l < kLanes; ++l) any += sf[l];
            if (any > 0) break;  // the caller clips the disc and sums again: these sums are moot
        }
    }
    Vec3f total{0, 0, 0};
    float found = 0, rejected = 0;
    for (int l = 0; l < kLanes; ++l) {
        total += Vec3f(sr[l], sg[l], sb[l]);
        found += sw[l];
        rejected += sf[l];
    }
    if (count) *count = found;
    if (foreign) *foreign = rejected;
    return total;
}

Vec3f AdaptiveGrid::sum_full_disc(const SurfaceDisc& d, float* count, float* foreign) const {
    return disc_sum<false, false>(d, count, foreign);
}

bool AdaptiveGrid::sum_full_disc_unless_foreign(const SurfaceDisc& d, Vec3f* sum, float* count) const {
    float foreign = 0;
    *sum = disc_sum<false, true>(d, count, &foreign);
    return foreign == 0;
}

Vec3f AdaptiveGrid::sum_disc(const SurfaceDisc& d, float* count, float* foreign) const {
    return disc_sum<true, false>(d, count, foreign);
}

Vec3f AdaptiveGrid::sum_in_radius(Vec3f q, float r2, float* count) const {
    return sum<false>(q, {0, 0, 0}, r2, count);
}

Vec3f AdaptiveGrid::sum_box(Vec3f q, Vec3f n, float r2, float* count) const {
    return sum<true>(q, n, r2, count);
}

}  // namespace gigascroll

#include "photon/hash_grid.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "photon/gather.h"

namespace gigascroll {

namespace {
// Beyond this many cells per axis int64 cell arithmetic could overflow: refuse the radius.
constexpr double kMaxCellsPerAxis = 1e15;
}

HashGrid::HashGrid(const std::vector<Photon>& photons, float radius, Mode mode) : r_(radius) {
    require(std::isfinite(radius) && radius > 0.0f, "HashGrid: radius must be positive and finite");
    inv_r_ = 1.0f / radius;
    const std::size_t n = photons.size();
    Vec3f lo{0, 0, 0}, hi{0, 0, 0};
    if (n > 0) {
        lo = hi = photons[0].p;
        for (const Photon& p : photons) {
            lo = vmin(lo, p.p);
            hi = vmax(hi, p.p);
        }
    }
    // Origin one cell (the padding layer) plus a little below the smallest photon.
    origin_ = lo - Vec3f(1, 1, 1) * (radius * 1.001f);
    double cells = 1;
    for (int a = 0; a < 3; ++a) {
        const double g = std::floor(double(hi[a] - origin_[a]) / double(radius)) + 2.0;  // + padding
        require(g < kMaxCellsPerAxis, "HashGrid: radius too small for the scene's extent");
        g_[a] = std::int64_t(g);
        cells *= g;
    }
    const double dense_limit = std::max<double>(double(1 << 22), 4.0 * double(n));
    dense_ = mode == Mode::Dense || (mode == Mode::Auto && cells <= dense_limit);
    if (dense_) require(cells <= double(1 << 27), "HashGrid: a dense grid would need more than 2^27 cells");

    if (dense_) {
        cells_ = std::uint64_t(cells);
    } else {
        buckets_ = 1;
        while (buckets_ < 2 * std::max<std::uint64_t>(n, 1)) buckets_ <<= 1;
    }
    std::vector<std::uint64_t> key(n);
    for (std::size_t i = 0; i < n; ++i) {
        std::int64_t c[3];
        cell_of(photons[i].p, c);
        key[i] = dense_ ? std::uint64_t((c[2] * g_[1] + c[1]) * g_[0] + c[0]) : bucket(c[0], c[1], c[2]);
    }
    sort_photons_by_key(photons, key, dense_ ? cells_ : buckets_, start_, photons_, {&px_, &py_, &pz_, &nx_, &ny_, &nz_, &pr_, &pg_, &pb_});
}

Vec3f HashGrid::sum_box(Vec3f q, Vec3f n, float r2, float* count) const {
    PhotonRun rs[27];
    const int nr = runs(q, rs);
    const float* px = px_.data(); const float* py = py_.data(); const float* pz = pz_.data();
    const float* nx = nx_.data(); const float* ny = ny_.data(); const float* nz = nz_.data();
    const float* pr = pr_.data(); const float* pg = pg_.data(); const float* pb = pb_.data();
    auto weight = [&](std::uint64_t j) {
        const float dx = px[j] - q.x, dy = py[j] - q.y, dz = pz[j] - q.z;
        const float d2 = dx * dx + dy * dy + dz * dz;
        const float agree = nx[j] * n.x + ny[j] * n.y + nz[j] * n.z;
        return float((d2 <= r2) & (agree > kNormalAgreement));
    };
    return sum_runs(rs, nr, pr, pg, pb, weight, count);
}

bool HashGrid::cell_of(Vec3f q, std::int64_t c[3]) const {
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
        const double f = std::floor(double(q[a] - origin_[a]) * double(inv_r_));
        // Clamp far-away points to just outside the grid so the arithmetic stays in range.
        const double cl = std::clamp(f, -2.0, double(g_[a]) + 1.0);
        c[a] = std::int64_t(cl);
        inside = inside && f >= 0 && f < double(g_[a]);
    }
    return inside;
}

std::uint64_t HashGrid::bucket(std::int64_t x, std::int64_t y, std::int64_t z) const {
    // pbrt-v4's SPPM hash (Teschner et al.'s primes), reduced to the power-of-two table.
    const std::uint64_t h = (std::uint64_t(x) * 73856093u) ^ (std::uint64_t(y) * 19349663u) ^
                            (std::uint64_t(z) * 83492791u);
    return (h ^ (h >> 29)) & (buckets_ - 1);
}

int HashGrid::runs(Vec3f q, PhotonRun out[27]) const {
    if (photons_.empty()) return 0;
    std::int64_t c[3];
    cell_of(q, c);
    int n = 0;
    if (dense_) {
        // The padding layer means interior queries never leave the grid; the clamps only
        // matter for query points outside the photons' bounding box.
        const std::int64_t x0 = std::max<std::int64_t>(c[0] - 1, 0), x1 = std::min(c[0] + 1, g_[0] - 1);
        if (x0 > x1) return 0;
        for (std::int64_t z = c[2] - 1; z <= c[2] + 1; ++z) {
            if (z < 0 || z >= g_[2]) continue;
            for (std::int64_t y = c[1] - 1; y <= c[1] + 1; ++y) {
                if (y < 0 || y >= g_[1]) continue;
                const std::uint64_t row = std::uint64_t((z * g_[1] + y) * g_[0]);
                const std::uint64_t b = start_[row + x0], e = start_[row + x1 + 1];
                if (b < e) out[n++] = {b, e};
            }
        }
        return n;
    }
    std::uint64_t ids[27];
    int m = 0;
    for (std::int64_t z = c[2] - 1; z <= c[2] + 1; ++z)
        for (std::int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
            for (std::int64_t x = c[0] - 1; x <= c[0] + 1; ++x) ids[m++] = bucket(x, y, z);
    // Two neighbouring cells may share a bucket: visit each bucket once.
    std::sort(ids, ids + m);
    m = int(std::unique(ids, ids + m) - ids);
    for (int i = 0; i < m; ++i) {
        const std::uint64_t b = start_[ids[i]], e = start_[ids[i] + 1];
        if (b < e) out[n++] = {b, e};
    }
    return n;
}

}  // namespace gigascroll

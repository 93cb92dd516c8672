// The final gather's bright spots as lights of their own: see hot_lattice.h.

#include "gallery/hot_lattice.h"

#include <algorithm>
#include <cmath>

namespace gigascroll {
namespace {
inline std::uint64_t point_index(std::uint32_t i, std::uint32_t j, std::uint32_t n) {
    return std::uint64_t(i) * (n + 1) - std::uint64_t(i) * (i - 1) / 2 + j;
}
// How many of the lattice's cells (up: (a, b), (a+1, b), (a, b+1), a + b < m; down: (a+1, b),
// (a, b+1), (a+1, b+1), a + b < m - 1) have (i, j) as a corner: 6 inside, fewer on the edges.
int cells_around(std::int64_t i, std::int64_t j, std::int64_t m) {
    auto up = [&](std::int64_t a, std::int64_t b) { return a >= 0 && b >= 0 && a + b < m; };
    auto down = [&](std::int64_t a, std::int64_t b) { return a >= 0 && b >= 0 && a + b < m - 1; };
    return int(up(i, j)) + up(i - 1, j) + up(i, j - 1) + down(i - 1, j) + down(i, j - 1) + down(i - 1, j - 1);
}
struct Candidate {
    float lum;
    std::uint32_t t, i, j;
    int side;
};
}  // namespace

HotLattice extract_hot_points(const Scene& scene, std::vector<Vec3f>& front, std::vector<Vec3f>& back,
                              const std::vector<std::uint64_t>& offset, const std::vector<std::uint32_t>& n,
                              const std::vector<Vec3f>& v0, const std::vector<Vec3f>& e1,
                              const std::vector<Vec3f>& e2, float factor, std::size_t max_points) {
    HotLattice hot;
    if (!(factor > 0) || max_points == 0) return hot;
    auto point = [&](std::uint32_t t, std::uint32_t i, std::uint32_t j) {
        return v0[t] + e1[t] * (float(i) / float(n[t])) + e2[t] * (float(j) / float(n[t]));
    };
    // The mean outgoing luminance over lit point sides (albedo: the triangle's constant one).
    double sum = 0;
    std::uint64_t lit = 0;
    for (std::size_t t = 0; t < n.size(); ++t) {
        const float a = luminance(scene.albedo(std::uint32_t(t)));
        if (!(a > 0)) continue;
        for (std::uint64_t q = offset[t]; q < offset[t + 1]; ++q)
            for (const Vec3f* E : {&front[q], &back[q]})
                if (luminance(*E) > 0) sum += a * luminance(*E), ++lit;
    }
    if (!lit || !(sum > 0)) return hot;
    const float threshold = float(factor * sum / double(lit));
    std::vector<Candidate> found;
    for (std::size_t t = 0; t < n.size(); ++t) {
        if (!(max_component(scene.albedo(std::uint32_t(t))) > 0)) continue;
        const std::uint32_t m = n[t];
        for (std::uint32_t i = 0; i <= m; ++i)
            for (std::uint32_t j = 0; i + j <= m; ++j)
                for (int side = 0; side < 2; ++side) {
                    const Vec3f E = (side == 0 ? front : back)[offset[t] + point_index(i, j, m)];
                    const Vec3f a = scene.albedo_at(std::uint32_t(t), point(std::uint32_t(t), i, j));
                    const float l = luminance(a * E);
                    if (l > threshold) found.push_back({l, std::uint32_t(t), i, j, side});
                }
    }
    if (found.size() > max_points) {
        std::nth_element(found.begin(), found.begin() + std::ptrdiff_t(max_points), found.end(),
                         [](const Candidate& x, const Candidate& y) { return x.lum > y.lum; });
        found.resize(max_points);
    }
    double total = 0;
    for (const Candidate& c : found) {
        const std::uint32_t m = n[c.t];
        Vec3f& E = (c.side == 0 ? front : back)[offset[c.t] + point_index(c.i, c.j, m)];
        const Vec3f p = point(c.t, c.i, c.j);
        const Vec3f N = scene.normal(c.t) * (c.side == 0 ? 1.0f : -1.0f);
        // The hat function's integral: a third of its cells' area (each |e1 x e2| / 2 / m^2).
        const float area = float(cells_around(c.i, c.j, m)) / 3.0f * length(cross(e1[c.t], e2[c.t])) / 2.0f /
                           float(m) / float(m);
        hot.position.push_back(p + N * (4 * scene.epsilon()));
        hot.normal.push_back(N);
        hot.area.push_back(area);
        hot.power.push_back(scene.albedo_at(c.t, p) * E * float(area / M_PI));
        total += luminance(hot.power.back());
        hot.cdf.push_back(float(total));
        E = Vec3f(0, 0, 0);
    }
    for (float& c : hot.cdf) c = float(c / total);
    return hot;
}

Vec3f hot_irradiance(const Scene& scene, const HotLattice& hot, Vec3f p, Vec3f nrm, int samples, double u) {
    const std::size_t count = hot.position.size();
    if (!count) return Vec3f(0, 0, 0);
    const bool all = count <= std::size_t(samples);
    const std::size_t draws = all ? count : std::size_t(samples);
    const Vec3f o = p + nrm * scene.epsilon();
    Vec3f E{0, 0, 0};
    for (std::size_t k = 0; k < draws; ++k) {
        std::size_t h = k;
        float weight = 1;  // 1 / (draws x pmf) when sampled
        if (!all) {
            const float x = float((double(k) + u) / double(draws));
            h = std::size_t(std::lower_bound(hot.cdf.begin(), hot.cdf.end(), x) - hot.cdf.begin());
            h = std::min(h, count - 1);
            const float pmf = hot.cdf[h] - (h ? hot.cdf[h - 1] : 0.0f);
            if (!(pmf > 0)) continue;
            weight = 1.0f / (float(draws) * pmf);
        }
        const Vec3f d = hot.position[h] - o;
        const float d2 = dot(d, d);
        if (!(d2 > 0)) continue;
        const float dist = std::sqrt(d2);
        const Vec3f w = d / dist;
        const float cx = dot(nrm, w), cy = -dot(hot.normal[h], w);
        if (!(cx > 0) || !(cy > 0)) continue;
        if (scene.occluded(o, w, dist * (1 - 1e-4f))) continue;
        // power = L x area: E += L area cos cos / d^2, d^2 no smaller than the area.
        E += hot.power[h] * (weight * cx * cy / std::max(d2, hot.area[h]));
    }
    return E;
}

}  // namespace gigascroll

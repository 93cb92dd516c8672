#include "photon/photon_map.h"

#include <algorithm>

#include "common/error.h"

namespace gigascroll::photon {

PhotonMap::PhotonMap(const std::vector<Photon>& photons, float radius, GridKind kind, HashGrid::Mode mode) {
    require(std::isfinite(radius) && radius > 0.0f, "PhotonMap: radius must be positive and finite");
    if (kind == GridKind::Hash) grid_ = std::make_unique<HashGrid>(photons, radius, mode);
    else kd_ = std::make_unique<KdTree>(photons);
}

std::vector<std::uint64_t> PhotonMap::query_radius(Vec3 q, float r) const {
    require(std::isfinite(r) && r > 0.0f, "PhotonMap.query_radius: radius must be positive");
    require(!grid_ || r <= grid_->radius(), "PhotonMap.query_radius: radius exceeds the grid's cell size");
    std::vector<std::uint64_t> out;
    const Photon* base = photons().data();
    float r2 = r * r;
    each(q, r2, [&](const Photon& p, float) { out.push_back(std::uint64_t(&p - base)); });
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::uint64_t> PhotonMap::query_knn(Vec3 q, int k, float r) const {
    require(k > 0, "PhotonMap.query_knn: k must be positive");
    require(std::isfinite(r) && r > 0.0f, "PhotonMap.query_knn: radius must be positive");
    require(!grid_ || r <= grid_->radius(), "PhotonMap.query_knn: radius exceeds the grid's cell size");
    std::vector<std::pair<float, std::uint64_t>> h;
    const Photon* base = photons().data();
    float r2 = r * r;
    each(q, r2, [&](const Photon& p, float d2) {
        const std::pair<float, std::uint64_t> item{d2, std::uint64_t(&p - base)};
        if (int(h.size()) < k) {
            h.push_back(item);
            std::push_heap(h.begin(), h.end());
            if (int(h.size()) == k) r2 = h.front().first;
        } else if (item < h.front()) {
            std::pop_heap(h.begin(), h.end());
            h.back() = item;
            std::push_heap(h.begin(), h.end());
            r2 = h.front().first;
        }
    });
    std::sort_heap(h.begin(), h.end());
    std::vector<std::uint64_t> out;
    for (const auto& it : h) out.push_back(it.second);
    return out;
}

}  // namespace gigascroll::photon

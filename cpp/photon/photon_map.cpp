#include "photon/photon_map.h"

#include <algorithm>

#include "common/error.h"

namespace gigascroll {

GridKind parse_grid_kind(const std::string& s) {
    if (s == "hash") return GridKind::Hash;
    if (s == "kdtree") return GridKind::KdTree;
    if (s == "adaptive") return GridKind::Adaptive;
    throw InvalidArgument("grid must be 'adaptive', 'hash' or 'kdtree', not '" + s + "'");
}

HashGrid::Mode parse_hash_mode(const std::string& s) {
    if (s == "auto") return HashGrid::Mode::Auto;
    if (s == "dense") return HashGrid::Mode::Dense;
    if (s == "hashed") return HashGrid::Mode::Hashed;
    throw InvalidArgument("hash_mode must be 'auto', 'dense' or 'hashed', not '" + s + "'");
}

bool parse_gather_is_knn(const std::string& s) {
    if (s == "radius" || s == "knn") return s == "knn";
    throw InvalidArgument("gather must be 'radius' or 'knn', not '" + s + "'");
}

PhotonMap::PhotonMap(const std::vector<Photon>& photons, float radius, GridKind kind, HashGrid::Mode mode,
                     PhotonMap* recycle, unsigned threads) {
    require(std::isfinite(radius) && radius > 0.0f, "PhotonMap: radius must be positive and finite");
    if (kind == GridKind::Hash) grid_ = std::make_unique<HashGrid>(photons, radius, mode);
    else if (kind == GridKind::Adaptive)
        adaptive_ = std::make_unique<AdaptiveGrid>(photons, radius, 0.0f,
                                                   recycle ? recycle->adaptive_.get() : nullptr, threads);
    else kd_ = std::make_unique<KdTree>(photons);
}

std::vector<std::uint64_t> PhotonMap::query_radius(Vec3f q, float r) const {
    require(std::isfinite(r) && r > 0.0f, "PhotonMap.query_radius: radius must be positive");
    require(kd_ || r <= build_radius(), "PhotonMap.query_radius: radius exceeds the grid's radius");
    std::vector<std::uint64_t> out;
    const Photon* base = photons().data();
    float r2 = r * r;
    each(q, r2, [&](const Photon& p, float) { out.push_back(std::uint64_t(&p - base)); });
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<std::uint64_t> PhotonMap::query_knn(Vec3f q, int k, float r) const {
    require(k > 0, "PhotonMap.query_knn: k must be positive");
    require(std::isfinite(r) && r > 0.0f, "PhotonMap.query_knn: radius must be positive");
    require(kd_ || r <= build_radius(), "PhotonMap.query_knn: radius exceeds the grid's radius");
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

}  // namespace gigascroll

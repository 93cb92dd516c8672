// Feedback buffers for the request-processing tests: random runs of keys over a few small
// paintings, and the brute-force answers to compare with.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "views/request_processing.h"

namespace gigascroll {

inline std::vector<std::uint64_t> sorted(std::vector<std::uint64_t> v) {
    std::sort(v.begin(), v.end());
    return v;
}

// Brute force: the distinct non-empty keys of the buffers.
inline std::set<std::uint64_t> distinct(const std::vector<std::vector<std::uint64_t>>& buffers) {
    std::set<std::uint64_t> s;
    for (const auto& b : buffers)
        for (auto k : b)
            if (k != kNoRequest) s.insert(k);
    return s;
}

inline std::vector<FeedbackBuffer> spans(const std::vector<std::vector<std::uint64_t>>& buffers) {
    return {buffers.begin(), buffers.end()};
}

// Random feedback: runs of equal keys (as neighbouring pixels give) and empty pixels.
inline std::vector<std::vector<std::uint64_t>> random_buffers(
    const std::vector<PaintingGeometry>& paintings, std::size_t count, std::size_t pixels,
    std::size_t distinct_keys, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::vector<std::uint64_t> pool;
    for (std::size_t i = 0; i < distinct_keys; ++i) {
        const auto p = std::uint32_t(rng() % paintings.size());
        const auto l = std::uint32_t(rng() % paintings[p].levels());
        pool.push_back(pack_request(p, l, std::uint32_t(rng() % paintings[p].tiles_x(l)),
                                    std::uint32_t(rng() % paintings[p].tiles_y(l))));
    }
    std::vector<std::vector<std::uint64_t>> out(count);
    for (auto& b : out) {
        while (b.size() < pixels) {
            const std::uint64_t k = rng() % 7 == 0 ? kNoRequest : pool[rng() % pool.size()];
            b.insert(b.end(), std::min<std::size_t>(1 + rng() % 9, pixels - b.size()), k);
        }
    }
    return out;
}

inline std::vector<PaintingGeometry> small_paintings() {
    return {PaintingGeometry(5000, 700), PaintingGeometry(1200, 3000), PaintingGeometry(800, 800, 64, 2)};
}

}  // namespace gigascroll

#include "display/stereo_reuse.h"

#include <limits>

namespace gigascroll {
namespace display {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
}  // namespace

bool rows_align(const Camera& left, const Camera& right) {
    auto same = [](const Vec3d& a, const Vec3d& b) { return length(a - b) <= 1e-12; };
    const Vec3d offset = right.position - left.position;
    const double apart = length(offset);
    return same(left.forward, right.forward) && same(left.up, right.up) && same(left.right, right.right) &&
           left.tan_half_y == right.tan_half_y && left.height == right.height &&
           std::abs(dot(offset, left.up)) <= 1e-9 * apart && std::abs(dot(offset, left.forward)) <= 1e-9 * apart;
}

void claimed_row_min(const std::uint64_t* __restrict claims, std::size_t w, float* __restrict depths,
                     float* __restrict row_min) {
    depths[0] = depths[w + 1] = kInf;
    // Each claim's depth (unclaimed: infinitely far), W claims at a time, then the rest.
    auto depth_lanes = [&]<int W>(std::size_t x0) {
        using L = Lanes<W>;
        std::size_t x = x0;
        for (; x + W <= w; x += W) {
            const ClaimLanes<W> c = load_claims(claims + x, std::integral_constant<int, W>{});
            L::select(c.unclaimed, typename L::F(kInf), c.depth).store(depths + x + 1);
        }
        return x;
    };
    depth_lanes.template operator()<1>(depth_lanes.template operator()<kWidest>(0));
    // std::min(a, b) is b < a ? b : a, the lanes' min(b, a).
    auto min_lanes = [&]<int W>(std::size_t x0) {
        using F = typename Lanes<W>::F;
        std::size_t x = x0;
        for (; x + W <= w; x += W)
            min(F::load(depths + x + 2), min(F::load(depths + x + 1), F::load(depths + x))).store(row_min + x);
        return x;
    };
    min_lanes.template operator()<1>(min_lanes.template operator()<kWidest>(0));
}

std::uint64_t release_claims(std::uint64_t* __restrict claims, const float* up, const float* mid,
                             const float* down, std::size_t w, float ratio,
                             std::int32_t* __restrict source, bool reset) {
    std::uint64_t kept = 0;
    // At most 8 lanes: on the development host the 16-lane form (two two-source permutes per
    // 16 claims) took a third longer than the 8-lane one (shuffles), the same results.
    constexpr int kReleaseWidth = kWidest < 8 ? kWidest : 8;
    const std::size_t x = release_claim_lanes<kReleaseWidth>(claims, up, mid, down, w, ratio, source, kept);
    release_claim_lanes<1>(claims + x, up + x, mid + x, down + x, w - x, ratio, source + x, kept);
    if (reset) std::fill_n(claims, w, kUnclaimed);
    return kept;
}

}  // namespace display
}  // namespace gigascroll

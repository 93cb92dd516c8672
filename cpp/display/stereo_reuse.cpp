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
    for (std::size_t x = 0; x < w; ++x) {
        const std::uint64_t c = claims[x];
        depths[x + 1] = c == kUnclaimed ? kInf : std::bit_cast<float>(std::uint32_t(c >> 32));
    }
    for (std::size_t x = 0; x < w; ++x)
        row_min[x] = std::min(std::min(depths[x], depths[x + 1]), depths[x + 2]);
}

std::uint64_t release_claims(std::uint64_t* __restrict claims, const float* up, const float* mid,
                             const float* down, std::size_t w, float ratio,
                             std::int32_t* __restrict source, bool reset) {
    std::uint64_t kept = 0;
    const std::size_t x = release_claim_lanes<kWidest>(claims, up, mid, down, w, ratio, source, kept);
    release_claim_lanes<1>(claims + x, up + x, mid + x, down + x, w - x, ratio, source + x, kept);
    if (reset) std::fill_n(claims, w, kUnclaimed);
    return kept;
}

}  // namespace display
}  // namespace gigascroll

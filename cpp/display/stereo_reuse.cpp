#include "display/stereo_reuse.h"

#include <limits>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

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
    std::size_t x = 0;
#if defined(__AVX2__)
    // 8 claims at once, the same comparisons (GCC keeps the loop below scalar). std::min(a, b)
    // is b < a ? b : a, which _mm256_min_ps(b, a) computes.
    const __m256 vratio = _mm256_set1_ps(ratio);
    const __m256i ones = _mm256_set1_epi64x(-1);
    for (; x + 8 <= w; x += 8) {
        const __m256 nearest = _mm256_min_ps(
            _mm256_loadu_ps(down + x),
            _mm256_min_ps(_mm256_loadu_ps(mid + x), _mm256_loadu_ps(up + x)));
        const __m256i c0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims + x));
        const __m256i c1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims + x + 4));
        // The claims' high words (depths), low words (left pixels) and unclaimed masks, in
        // pixel order: per 128-bit lane the odd (even) words of c0 and c1, then the 64-bit
        // quarters reordered.
        auto odd_words = [](__m256i a, __m256i b) {
            return _mm256_castpd_si256(_mm256_permute4x64_pd(
                _mm256_castps_pd(_mm256_shuffle_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b),
                                                   _MM_SHUFFLE(3, 1, 3, 1))),
                _MM_SHUFFLE(3, 1, 2, 0)));
        };
        auto even_words = [](__m256i a, __m256i b) {
            return _mm256_castpd_si256(_mm256_permute4x64_pd(
                _mm256_castps_pd(_mm256_shuffle_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b),
                                                   _MM_SHUFFLE(2, 0, 2, 0))),
                _MM_SHUFFLE(3, 1, 2, 0)));
        };
        const __m256 depth = _mm256_castsi256_ps(odd_words(c0, c1));
        const __m256i index = even_words(c0, c1);
        const __m256i unclaimed = odd_words(_mm256_cmpeq_epi64(c0, ones), _mm256_cmpeq_epi64(c1, ones));
        const __m256 far = _mm256_cmp_ps(depth, _mm256_mul_ps(nearest, vratio), _CMP_GT_OQ);
        const __m256 drop = _mm256_or_ps(far, _mm256_castsi256_ps(unclaimed));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(source + x),
                            _mm256_castps_si256(_mm256_blendv_ps(
                                _mm256_castsi256_ps(index), _mm256_castsi256_ps(ones), drop)));
        kept += 8 - std::uint64_t(std::popcount(unsigned(_mm256_movemask_ps(drop))));
    }
#endif
    for (; x < w; ++x) {
        const float nearest = std::min(std::min(up[x], mid[x]), down[x]);
        const std::uint64_t c = claims[x];
        const bool keep = c != kUnclaimed &&
                          !(std::bit_cast<float>(std::uint32_t(c >> 32)) > nearest * ratio);
        source[x] = keep ? std::int32_t(c & 0xffffffffu) : -1;
        kept += keep;
    }
    if (reset) std::fill_n(claims, w, kUnclaimed);
    return kept;
}

}  // namespace display
}  // namespace gigascroll

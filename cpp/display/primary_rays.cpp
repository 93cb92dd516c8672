#include "display/primary_rays.h"

#include <atomic>

#include "common/error.h"
#include "common/parallel.h"
#include "common/timing.h"

namespace gigascroll {

using namespace display;
namespace display {

void check_camera(const Camera& eye) {
    require(eye.width > 0 && eye.height > 0, "display: the eye's resolution must be positive");
    require(std::uint64_t(eye.width) * eye.height < (std::uint64_t(1) << 31),
            "display: at most 2^31 pixels per eye");
}

// Rows per parallel chunk of one eye's pass alone, the display's and the bare cast's alike:
// 16, so that a chunk's rows run one after another on one core (the texel rows sample16
// fetches ahead for the next screen row are read there, not by the other core) and a chunk's
// set-up is paid once per 16 rows; fewer for a short image, so that each thread still takes
// about 8 chunks (the last chunk's wait stays small).
std::size_t rows_per_chunk(std::size_t height, unsigned threads) {
    const std::size_t workers = threads ? threads : default_threads();
    return std::clamp<std::size_t>(height / (8 * workers), 4, 16);
}

}  // namespace display

double cast_primary_rays(RTCScene scene, const Camera& eye, unsigned threads, std::uint64_t* hits) {
    require(scene != nullptr, "cast_primary_rays: the scene has no BVH");
    check_camera(eye);
    const auto t0 = Clock::now();
    std::atomic<std::uint64_t> total{0};
    parallel_for(eye.height, rows_per_chunk(eye.height, threads), [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0;
        cast_rows(scene, eye, rb, re, nullptr, false, [](std::size_t) {},
                  [&](std::size_t, std::uint32_t, std::uint32_t n,
                                                   const int*, const RTCRayHit16& h) {
            for (std::uint32_t k = 0; k < n; ++k) count += h.hit.geomID[k] != kNoHit;
        }, [](std::size_t) {});
        total.fetch_add(count, std::memory_order_relaxed);
    }, threads);
    if (hits) *hits = total.load();
    return seconds_since(t0);
}

}  // namespace gigascroll

// Upper bounds of the values that enter the core from users, checked where they enter so that
// no ray reaches Embree invalid and no size allocates before it has been compared with a limit.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "common/error.h"
#include "common/vec3.h"

namespace gigascroll {

// Largest coordinate (in scene units, metres) of a camera, a vertex or a ray origin. Embree
// aborts on rays whose origin or direction exceeds about 1.8e18 (its ray.valid() check), and
// single precision has no useful resolution long before: 1e12 keeps every point o + t d of a
// ray between two bounded points far inside Embree's range.
inline constexpr double kMaxCoordinate = 1e12;
// Largest tangent of a camera's half field of view (179.9999 degrees): ray directions
// forward + sx right + sy up stay finite in single precision.
inline constexpr double kMaxTanHalfFov = 1e6;
// Largest thread count any call accepts (the machine's cores are far fewer).
inline constexpr std::uint64_t kMaxThreads = 1024;

inline bool within_coordinate_bound(Vec3d p) {
    return is_finite(p) && std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
           std::abs(p.z) <= kMaxCoordinate;
}
inline bool within_coordinate_bound(Vec3f p) { return within_coordinate_bound(Vec3d(p)); }

// "what must be finite (no NaN or Inf) and within +-1e12 (got (x, y, z))" unless p is.
inline void require_coordinate(Vec3d p, const std::string& what) {
    if (within_coordinate_bound(p)) return;
    char buf[160];
    std::snprintf(buf, sizeof buf, " must be finite (no NaN or Inf) and within +-1e12 (got (%g, %g, %g))", p.x, p.y, p.z);
    throw InvalidArgument(what + buf);
}

inline void require_threads(std::uint64_t threads, const std::string& what) {
    require(threads <= kMaxThreads, what + ": threads must be at most " + std::to_string(kMaxThreads) +
                                        " (0 = all cores), got " + std::to_string(threads));
}

// Human-readable size: "3.2 GiB".
inline std::string format_bytes(double bytes) {
    const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    while (bytes >= 1024 && u < 6) bytes /= 1024, ++u;
    char buf[32];
    std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", bytes, unit[u]);
    return buf;
}

// Throws InvalidArgument unless count elements of elem_bytes each fit in max_bytes; the
// message says what the request would need. Computed in double: count may be near 2^64.
inline void require_memory(double count, double elem_bytes, double max_bytes, const std::string& what) {
    const double need = count * elem_bytes;
    if (need <= max_bytes) return;
    throw InvalidArgument(what + " would need " + format_bytes(need) + ", more than the limit of " +
                          format_bytes(max_bytes));
}

}  // namespace gigascroll

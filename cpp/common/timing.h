// Wall-clock timing of stages (the per-frame and per-pass figures the benchmarks report).
#pragma once
#include <chrono>
#include <cstdint>
#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
#endif

namespace gigascroll {

using Clock = std::chrono::steady_clock;

// Seconds elapsed since t0.
inline double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A cheap monotonic tick count for splitting a measured wall time among stages in
// proportion (only ratios of ticks are meaningful): the time-stamp counter where there is one
// (a few cycles, against ~25 ns for a clock read in a virtual machine), else nanoseconds.
inline std::uint64_t stage_ticks() {
#if defined(__x86_64__) || defined(__i386__)
    return __rdtsc();
#else
    return std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                             Clock::now().time_since_epoch()).count());
#endif
}

}  // namespace gigascroll

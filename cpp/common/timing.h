// Wall-clock timing of stages (the per-frame and per-pass figures the benchmarks report).
#pragma once
#include <chrono>

namespace gigascroll {

using Clock = std::chrono::steady_clock;

// Seconds elapsed since t0.
inline double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace gigascroll

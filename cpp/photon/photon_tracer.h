// Photon tracing (seed 001 pass 1): photons leave the emitters, bounce diffusely with
// Russian roulette and are stored at diffuse hits after their first bounce (the first hit is
// direct light, which the renderer computes by light sampling instead).
#pragma once
#include <cstdint>
#include <vector>

#include "photon/scene.h"

namespace gigascroll {

struct Photon {
    Vec3f p;      // position
    Vec3f power;  // flux carried (W, per RGB channel)
    Vec3f n;      // surface normal on the side the photon arrived from
};

struct TraceStats {
    std::uint64_t emitted = 0;
    std::uint64_t stored = 0;
    Vec3f emitted_power{0, 0, 0};  // total flux of all emitted photons (= the scene's power)
};

// Traces `count` photons on `threads` threads (0 = all cores). Photon i draws its random
// numbers from (seed, i) alone and the result is concatenated in photon order, so the output
// is identical for any thread count; `pass` selects an independent photon set of the same
// seed (progressive rendering traces one per pass). max_bounces caps a path (a safety net: with albedo < 1
// Russian roulette ends every path with probability one).
std::vector<Photon> trace_photons(const Scene& scene, std::uint64_t count, std::uint64_t seed,
                                  unsigned threads = 0, TraceStats* stats = nullptr,
                                  std::uint32_t pass = 0, int max_bounces = 256);

// A cosine-distributed direction around n from two uniforms.
Vec3f sample_cosine(Vec3f n, float u1, float u2);

}  // namespace gigascroll

// Photon tracing (VR-photon-mapping pass 1): photons leave the emitters, bounce diffusely with
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

// Photons emitted by one call (one pass): at most 2^32.
inline constexpr std::uint64_t kMaxEmittedPhotons = std::uint64_t(1) << 32;
// Default budget of stored photons of one call: 2^26 photons, 2.25 GiB.
inline constexpr std::uint64_t kDefaultStoredPhotonBudget = std::uint64_t(1) << 26;

// Traces `count` photons on `threads` threads (0 = all cores). Photon i draws its random
// numbers from (seed, i) alone and the result is concatenated in photon order, so the output
// is identical for any thread count; `pass` selects an independent photon set of the same
// seed (progressive rendering traces one per pass). Paths end by Russian roulette alone (no
// bounce cap, so the estimate stays unbiased at any albedo < 1): a photon stores on average
// a / (1 - a) copies in a closed room of albedo a. Memory is bounded by what is actually
// stored: past max_stored photons the trace stops with an InvalidArgument naming the memory.
std::vector<Photon> trace_photons(const Scene& scene, std::uint64_t count, std::uint64_t seed,
                                  unsigned threads = 0, TraceStats* stats = nullptr,
                                  std::uint32_t pass = 0,
                                  std::uint64_t max_stored = kDefaultStoredPhotonBudget);

// The same into `out` (its previous contents dropped, its capacity kept): a caller that traces
// repeatedly (a gallery relit) reuses the memory instead of faulting in fresh pages each time.
void trace_photons(std::vector<Photon>& out, const Scene& scene, std::uint64_t count, std::uint64_t seed,
                   unsigned threads = 0, TraceStats* stats = nullptr, std::uint32_t pass = 0,
                   std::uint64_t max_stored = kDefaultStoredPhotonBudget);

// A cosine-distributed direction around n from two uniforms.
Vec3f sample_cosine(Vec3f n, float u1, float u2);

}  // namespace gigascroll

// Random photons over [-extent, extent] in x and y and 0.3 of that in z: clustered in z,
// like photons on surfaces.
#pragma once
#include <cstddef>
#include <random>
#include <vector>

#include "photon/photon_tracer.h"

namespace gigascroll {

inline std::vector<Photon> random_photons(std::size_t n, unsigned seed, float extent = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-extent, extent);
    std::vector<Photon> ph(n);
    for (auto& p : ph) {
        p.p = {u(rng), u(rng), u(rng) * 0.3f};  // clustered in z, like photons on surfaces
        p.power = {1, 1, 1};
        p.n = {0, 0, 1};
    }
    return ph;
}

}  // namespace gigascroll

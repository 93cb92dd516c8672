// Density estimation over a photon map (VR-photon-mapping eq. 1):
//   L_r(x, w) ~ f_r / (pi r^2) * sum_p w_p Phi_p,   f_r = albedo / pi for Lambertian surfaces.
// The functions here return the flux density E = sum_p w_p Phi_p / (norm * pi r^2); the
// renderer multiplies by albedo / pi.
//  - radius gather: every photon within r, no heap (VR-photon-mapping's fast path);
//  - k-nearest gather: a max-heap of the k closest photons within r, and the radius shrinks
//    to the k-th distance once the heap is full (Jensen).
// Kernels: box (w = 1) and cone (w = 1 - d / r, norm = 1 - 2/3, Jensen's k = 1 filter).
// Photons whose surface normal disagrees with the query's are rejected: they lie on another
// surface (the back of a thin wall, the other side of a corner).
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/error.h"

#include "photon/photon_tracer.h"

namespace gigascroll {

enum class Kernel { Box, Cone };
// "box" / "cone"; InvalidArgument otherwise.
inline Kernel parse_kernel(const std::string& s) {
    if (s == "box") return Kernel::Box;
    if (s == "cone") return Kernel::Cone;
    throw InvalidArgument("kernel must be 'box' or 'cone', not '" + s + "'");
}

// cos of the largest angle between photon and surface normals that still counts.
constexpr float kNormalAgreement = 0.5f;

inline bool normals_agree(Vec3f photon_n, Vec3f n) { return dot(photon_n, n) > kNormalAgreement; }

inline float kernel_weight(Kernel k, float d2, float r2) {
    return k == Kernel::Box ? 1.0f : 1.0f - std::sqrt(d2 / r2);
}
inline float kernel_norm(Kernel k) { return k == Kernel::Box ? 1.0f : 1.0f / 3.0f; }

template <typename Map>
Vec3f gather_radius(const Map& map, Vec3f x, Vec3f n, float r, Kernel kernel) {
    float r2 = r * r;
    Vec3f sum{0, 0, 0};
    if (kernel == Kernel::Box) {
        map.for_each_in_radius(x, r2, [&](const Photon& p, float) {
            if (normals_agree(p.n, n)) sum += p.power;
        });
    } else {
        const float inv_r = 1.0f / r;
        map.for_each_in_radius(x, r2, [&](const Photon& p, float d2) {
            if (normals_agree(p.n, n)) sum += p.power * (1.0f - std::sqrt(d2) * inv_r);
        });
    }
    return sum * (1.0f / (kernel_norm(kernel) * float(M_PI) * r * r));
}

// Scratch space for one thread's k-nearest searches.
struct KnnHeap {
    std::vector<std::pair<float, const Photon*>> items;
};

template <typename Map>
Vec3f gather_knn(const Map& map, Vec3f x, Vec3f n, float r, int k, Kernel kernel, KnnHeap& heap) {
    auto& h = heap.items;
    h.clear();
    float r2 = r * r;
    const auto less = [](const auto& a, const auto& b) { return a.first < b.first; };
    map.for_each_in_radius(x, r2, [&](const Photon& p, float d2) {
        if (!normals_agree(p.n, n)) return;
        if (int(h.size()) < k) {
            h.emplace_back(d2, &p);
            std::push_heap(h.begin(), h.end(), less);
            if (int(h.size()) == k) r2 = h.front().first;  // shrink to the k-th distance
        } else if (d2 < h.front().first) {
            std::pop_heap(h.begin(), h.end(), less);
            h.back() = {d2, &p};
            std::push_heap(h.begin(), h.end(), less);
            r2 = h.front().first;
        }
    });
    if (h.empty()) return {0, 0, 0};
    // With a full heap the estimate's disc is the k-th distance; otherwise it is r.
    const float rk2 = int(h.size()) == k ? std::max(h.front().first, 1e-30f) : r * r;
    Vec3f sum{0, 0, 0};
    for (const auto& [d2, p] : h) sum += p->power * kernel_weight(kernel, d2, rk2);
    return sum * (1.0f / (kernel_norm(kernel) * float(M_PI) * rk2));
}

}  // namespace gigascroll

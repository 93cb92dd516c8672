// Jensen's photon-map baseline: a balanced kd-tree stored in an array. The median of each
// range [lo, hi) sits at its middle, split on the axis of largest extent, so the tree needs
// no pointers; k-nearest search keeps a max-heap of the k closest photons.
#pragma once
#include <cstdint>
#include <vector>

#include "photon/photon_tracer.h"

namespace gigascroll {

class KdTree {
public:
    explicit KdTree(const std::vector<Photon>& photons);

    std::size_t size() const { return photons_.size(); }
    const std::vector<Photon>& photons() const { return photons_; }

    // Calls f(photon, d2) for every photon with d2 <= r2; f may shrink r2, which prunes the
    // remaining search (k-nearest search does).
    template <typename F>
    void for_each_in_radius(Vec3f q, float& r2, F&& f) const {
        if (!photons_.empty()) visit(0, photons_.size(), q, r2, f);
    }

private:
    template <typename F>
    void visit(std::size_t lo, std::size_t hi, Vec3f q, float& r2, F& f) const {
        while (hi > lo) {
            const std::size_t mid = lo + (hi - lo) / 2;
            const Photon& p = photons_[mid];
            const int axis = axis_[mid];
            const float delta = q[axis] - p.p[axis];
            // Near side first, so a shrinking r2 prunes more of the far side.
            const std::size_t nlo = delta < 0 ? lo : mid + 1, nhi = delta < 0 ? mid : hi;
            const std::size_t flo = delta < 0 ? mid + 1 : lo, fhi = delta < 0 ? hi : mid;
            visit(nlo, nhi, q, r2, f);
            const Vec3f d = p.p - q;
            const float d2 = dot(d, d);
            if (d2 <= r2) f(p, d2);
            if (delta * delta > r2) return;
            lo = flo;
            hi = fhi;
        }
    }
    void build(std::size_t lo, std::size_t hi);

    std::vector<Photon> photons_;
    std::vector<std::uint8_t> axis_;
};

}  // namespace gigascroll

#include "photon/kd_tree.h"

#include <algorithm>

namespace gigascroll {

KdTree::KdTree(const std::vector<Photon>& photons) : photons_(photons), axis_(photons.size(), 0) {
    build(0, photons_.size());
}

void KdTree::build(std::size_t lo, std::size_t hi) {
    // Iterative on the larger half keeps the recursion depth at log2(n).
    while (hi - lo > 1) {
        Vec3f bmin = photons_[lo].p, bmax = bmin;
        for (std::size_t i = lo + 1; i < hi; ++i) {
            bmin = vmin(bmin, photons_[i].p);
            bmax = vmax(bmax, photons_[i].p);
        }
        const Vec3f ext = bmax - bmin;
        const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        const std::size_t mid = lo + (hi - lo) / 2;
        std::nth_element(photons_.begin() + std::ptrdiff_t(lo), photons_.begin() + std::ptrdiff_t(mid),
                         photons_.begin() + std::ptrdiff_t(hi),
                         [axis](const Photon& a, const Photon& b) { return a.p[axis] < b.p[axis]; });
        axis_[mid] = std::uint8_t(axis);
        if (mid - lo < hi - mid - 1) {
            build(lo, mid);
            lo = mid + 1;
        } else {
            build(mid + 1, hi);
            hi = mid;
        }
    }
}

}  // namespace gigascroll

// A photon grid whose cells are sized from the photon density and culled against the query
// sphere, with the photons in cell order as structure of arrays.
//
// VR-photon-mapping's grid (hash_grid.h) uses cells as wide as the radius and visits 3x3x3 of them: a
// query tests 27 / (4/3 pi) = 6.4 times the photons inside its sphere (about 3x for photons on
// a plane). Here the cell edge is r / k with k chosen from the expected number of photons per
// query (k = 1/4 when a query finds a handful and the cell lookups dominate, up to 3 when it
// finds thousands and the distance tests do), and a query walks only the rows of cells (z, y)
// that the sphere touches, each row cut to the x-range of the sphere's chord through it: one
// contiguous run per row. The distance tests then read positions, normals and power from
// separate arrays, so they vectorise.
//
// Queries may use any radius up to radius(): the rows are culled against the query's own
// sphere (the progressive estimator's shrinking per-pixel radii profit from it). The culling
// is conservative (padded by more than the float rounding of cell coordinates), so every
// photon with squared distance <= r2 is found: exactly the set brute force finds.
#pragma once
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <vector>

#include "photon/hash_grid.h"
#include "photon/photon_tracer.h"
#include "photon/surface_disc.h"

namespace gigascroll {

class AdaptiveGrid {
public:
    // Cells per radius are limited to [1/4, 4]; a query visits at most kMaxRuns rows.
    static constexpr float kMaxCellsPerRadius = 4.0f;
    static constexpr int kMaxRuns = (2 * 4 + 3) * (2 * 4 + 3);

    // cells_per_radius = r / cell edge; 0 chooses it from the photons' density. The grid is
    // dense; when its cells would exceed max(2^16, 4 * photons) the cells are made coarser.
    // recycle (if given) hands over its storage, whose capacity the new grid reuses (a
    // gallery relit: no fresh pages to fault in); it is left without photons, only to be destroyed.
    // threads (0: all cores) build it: the same grid on any number (counting_sort).
    AdaptiveGrid(const std::vector<Photon>& photons, float radius, float cells_per_radius = 0,
                 AdaptiveGrid* recycle = nullptr, unsigned threads = 1);

    float radius() const { return r_; }
    float cell_edge() const { return h_; }
    float cells_per_radius() const { return r_ / h_; }
    std::size_t size() const { return photons_.size(); }
    std::uint64_t cell_count() const { return start_.empty() ? 0 : start_.size() - 1; }
    // The photons in cell order (the order the runs index).
    const std::vector<Photon>& photons() const { return photons_; }

    // The runs holding every photon within r <= radius() of q (and others near the sphere:
    // callers test the distance). Writes at most kMaxRuns runs; returns how many.
    int runs(Vec3f q, float r, PhotonRun* out) const;

    // Calls f(photon, d2) for each photon with squared distance d2 <= r2 (r2 <= radius()^2).
    // f may shrink r2 (k-nearest search does).
    template <typename F>
    void for_each_in_radius(Vec3f q, float& r2, F&& f) const {
        PhotonRun rs[kMaxRuns];
        const int n = runs(q, std::sqrt(r2), rs);
        for (int i = 0; i < n; ++i)
            for (std::uint64_t j = rs[i].begin; j < rs[i].end; ++j) {
                const Photon& p = photons_[j];
                const Vec3f d = p.p - q;
                const float d2 = dot(d, d);
                if (d2 <= r2) f(p, d2);
            }
    }

    // The summed power of the photons with squared distance <= r2 of q, vectorised over the
    // arrays; *count (if given) receives how many.
    Vec3f sum_in_radius(Vec3f q, float r2, float* count = nullptr) const;
    // The same restricted to photons whose normals agree with n (gather.h's box gather).
    Vec3f sum_box(Vec3f q, Vec3f n, float r2, float* count = nullptr) const;

    // The first, unclipped pass of the surface-disc gather (surface_disc.h) vectorised: the
    // summed power of the photons within d.r of d.x that gather_disc(*this, d) accepts
    // (normals agree and d.contains), their count in *count and in *foreign how many within
    // d.r it rejects. d must be unclipped (full_surface_disc). The same photons as gather_disc.
    Vec3f sum_full_disc(const SurfaceDisc& d, float* count, float* foreign) const;
    // The same pass for gather_surface_disc, which needs its sums only when no photon is
    // foreign: true and sum_full_disc's sum and count when none is, false (sum and count
    // meaningless) as soon as a row of cells holds one.
    bool sum_full_disc_unless_foreign(const SurfaceDisc& d, Vec3f* sum, float* count) const;
    // The second, clipped pass (make_surface_disc) vectorised the same way: what
    // gather_disc(*this, d, count, foreign) sums, for any disc.
    Vec3f sum_disc(const SurfaceDisc& d, float* count, float* foreign = nullptr) const;

private:
    template <bool Clipped, bool StopAtForeign>
    Vec3f disc_sum(const SurfaceDisc& d, float* count, float* foreign) const;
    template <bool CheckNormal>
    Vec3f sum(Vec3f q, Vec3f n, float r2, float* count) const;
    // positions_only: start_ and px_, py_, pz_ alone, for count_in_radius.
    void build(const std::vector<Photon>& photons, float edge, bool positions_only, unsigned threads);
    // How many photons lie within sqrt(r2) of q (what sum_in_radius counts).
    std::uint64_t count_in_radius(Vec3f q, float r2) const;
    std::uint64_t cells_for(float edge) const;

    float r_ = 0, h_ = 0, inv_h_ = 0, pad_ = 0;
    Vec3f lo_, hi_, origin_;
    std::int64_t g_[3] = {0, 0, 0};
    std::vector<std::uint32_t> start_;  // prefix sums over the cells, one more than cells
    std::vector<Photon> photons_;
    std::vector<float> px_, py_, pz_, nx_, ny_, nz_, pr_, pg_, pb_;
};

}  // namespace gigascroll

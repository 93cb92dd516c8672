// A photon map: the stored photons behind one of the search structures (the adaptive grid,
// the renders' default; VR-photon-mapping's hash grid; Jensen's kd-tree), with the gathers of gather.h
// dispatched on the settings.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "photon/adaptive_grid.h"
#include "photon/gather.h"
#include "photon/hash_grid.h"
#include "photon/kd_tree.h"
#include "photon/surface_disc.h"

namespace gigascroll {

enum class GridKind { Hash, KdTree, Adaptive };
// "hash" / "kdtree" / "adaptive"; InvalidArgument otherwise.
GridKind parse_grid_kind(const std::string& name);
// "auto" / "dense" / "hashed"; InvalidArgument otherwise.
HashGrid::Mode parse_hash_mode(const std::string& name);
// "radius" (false) / "knn" (true); InvalidArgument otherwise.
bool parse_gather_is_knn(const std::string& name);

struct GatherSettings {
    float radius = 0.05f;
    bool knn = false;  // k-nearest with a heap instead of the heap-free radius gather
    int k = 50;
    Kernel kernel = Kernel::Box;
    bool disc = false;  // gather over the surface disc (surface_disc.h) instead of the sphere
};

class PhotonMap {
public:
    // recycle (if given): a map about to be destroyed whose adaptive grid's storage the new
    // adaptive grid reuses (AdaptiveGrid's recycle); threads build the adaptive grid (0: all
    // cores; the same grid on any number).
    PhotonMap(const std::vector<Photon>& photons, float radius, GridKind kind,
              HashGrid::Mode mode = HashGrid::Mode::Auto, PhotonMap* recycle = nullptr, unsigned threads = 1);

    std::size_t size() const { return photons().size(); }
    // The structure in use: exactly one of these is not null.
    const HashGrid* grid() const { return grid_.get(); }
    const KdTree* kdtree() const { return kd_.get(); }
    const AdaptiveGrid* adaptive() const { return adaptive_.get(); }

    // Flux density at x on a surface with normal n (see gather.h).
    Vec3f gather(Vec3f x, Vec3f n, const GatherSettings& s, KnnHeap& heap) const {
        const float box_norm = 1.0f / (float(M_PI) * s.radius * s.radius);
        if (adaptive_) {
            if (!s.knn && s.kernel == Kernel::Box) return adaptive_->sum_box(x, n, s.radius * s.radius) * box_norm;
            return s.knn ? gather_knn(*adaptive_, x, n, s.radius, s.k, s.kernel, heap)
                         : gather_radius(*adaptive_, x, n, s.radius, s.kernel);
        }
        if (grid_ && !s.knn && s.kernel == Kernel::Box)  // the hot path, vectorised
            return grid_->sum_box(x, n, s.radius * s.radius) * box_norm;
        if (grid_) return s.knn ? gather_knn(*grid_, x, n, s.radius, s.k, s.kernel, heap)
                                : gather_radius(*grid_, x, n, s.radius, s.kernel);
        return s.knn ? gather_knn(*kd_, x, n, s.radius, s.k, s.kernel, heap)
                     : gather_radius(*kd_, x, n, s.radius, s.kernel);
    }

    // The surface-disc gather (surface_disc.h) at x, radius at most the grid's.
    DiscEstimate gather_surface_disc(const Scene& scene, Vec3f x, Vec3f n, float r,
                                     SurfaceDisc::Detail detail = SurfaceDisc::Detail::Fine) const {
        if (adaptive_) return gigascroll::gather_surface_disc(scene, *adaptive_, x, n, r, detail);
        return grid_ ? gigascroll::gather_surface_disc(scene, *grid_, x, n, r, detail)
                     : gigascroll::gather_surface_disc(scene, *kd_, x, n, r, detail);
    }

    // Indices (into photons()) of every photon within r of q, for tests against brute force.
    std::vector<std::uint64_t> query_radius(Vec3f q, float r) const;
    // The k nearest photons within r, nearest first.
    std::vector<std::uint64_t> query_knn(Vec3f q, int k, float r) const;
    const std::vector<Photon>& photons() const {
        return adaptive_ ? adaptive_->photons() : grid_ ? grid_->photons() : kd_->photons();
    }
    // The radius the structure was built for (queries may not exceed it); 0 for the kd-tree.
    float build_radius() const { return adaptive_ ? adaptive_->radius() : grid_ ? grid_->radius() : 0.0f; }

private:
    template <typename F>
    void each(Vec3f q, float& r2, F&& f) const {
        if (adaptive_) adaptive_->for_each_in_radius(q, r2, f);
        else if (grid_) grid_->for_each_in_radius(q, r2, f);
        else kd_->for_each_in_radius(q, r2, f);
    }
    std::unique_ptr<HashGrid> grid_;
    std::unique_ptr<KdTree> kd_;
    std::unique_ptr<AdaptiveGrid> adaptive_;
};

}  // namespace gigascroll

// The exhibition room as an Embree scene: paintings are rectangles of their physical size
// (textured with their tile pyramid), boxes and tables only occlude. The feedback pass casts
// rays into it to find which painting texel each pixel sees.
#pragma once
#include <embree3/rtcore.h>

#include <cstdint>
#include <span>
#include <vector>

#include "pack/geometry.h"
#include "common/embree_device.h"
#include "common/vec3.h"

namespace gigascroll {

// Where a painting hangs or lies. Texel (0, 0) is at `origin`; image x runs along `u_axis`
// for width_m metres, image y (downwards in the image) along `v_axis` for height_m metres.
struct PaintingPlacement {
    std::uint32_t painting;  // the painting id p used in request keys
    PaintingGeometry tiles;
    Vec3d origin, u_axis, v_axis;
    double width_m, height_m;
    Vec3d normal() const { return cross(u_axis, v_axis); }
};

// What the feedback pass needs of a scene: an Embree BVH, the paintings in it and which
// Embree geometry shows which painting. The feedback pass takes this view rather than a
// scene class so that any scene holding paintings can feed it: the ExhibitionScene here,
// and the Gallery (gallery/), whose one BVH of room triangles and painting rectangles lives
// in the photon Scene. views/ comes before photon/ and gallery/ in the include order, so the
// view is a plain struct of pointers that the owner keeps alive while the pass runs.
struct PaintingSceneView {
    RTCScene handle = nullptr;
    std::span<const PaintingPlacement> paintings;
    std::span<const int> geom_placement;  // placement index per Embree geometry id, -1 = none
    // The world position of the BVH's coordinate origin: the Gallery holds a room far from the
    // world's origin in coordinates around the room (float keeps its precision there; see
    // Gallery::origin). Passes take world cameras and cast from camera.moved(-origin).
    Vec3d origin{0, 0, 0};
    int placement_of(unsigned geom_id) const {
        return geom_id < geom_placement.size() ? geom_placement[geom_id] : -1;
    }
};

class ExhibitionScene {
public:
    ExhibitionScene();
    ~ExhibitionScene();
    ExhibitionScene(const ExhibitionScene&) = delete;
    ExhibitionScene& operator=(const ExhibitionScene&) = delete;

    // Returns the placement index. u_axis and v_axis must be orthonormal.
    std::size_t add_painting(std::uint32_t painting, const PaintingGeometry& tiles, Vec3d origin,
                             Vec3d u_axis, Vec3d v_axis, double width_m, double height_m);
    // An axis-aligned occluder (walls, plinths, the seed's "simple cuboids").
    void add_box(Vec3d lo, Vec3d hi);
    // A table: a 4 cm top whose upper face is at `height` (0.70 m in VT-mobile-VR) and four legs;
    // centred at (x, z) on the floor y = 0, `length` along x and `depth` along z.
    void add_table(double x, double z, double length, double depth, double height = 0.70);

    // Builds the BVH; call once after adding geometry and before casting rays.
    void commit();
    bool committed() const { return committed_; }

    RTCScene handle() const { return scene_; }
    const std::vector<PaintingPlacement>& paintings() const { return paintings_; }
    // Placement index of an Embree geometry id, or -1 for occluders.
    int placement_of(unsigned geom_id) const {
        return geom_id < geom_placement_.size() ? geom_placement_[geom_id] : -1;
    }
    std::size_t box_count() const { return boxes_; }
    // The scene as the feedback pass sees it (valid while the scene lives).
    PaintingSceneView view() const { return {scene_, paintings_, geom_placement_}; }

private:
    unsigned add_quads(const std::vector<Vec3d>& vertices, std::size_t quads);
    void require_open() const;

    EmbreeDevice device_;
    RTCScene scene_ = nullptr;
    std::vector<PaintingPlacement> paintings_;
    std::vector<int> geom_placement_;
    std::size_t boxes_ = 0;
    bool committed_ = false;
};

}  // namespace gigascroll

#include "views/exhibition.h"

#include <cmath>
#include <string>

#include "common/error.h"
#include "common/limits.h"
#include "pack/tile_key.h"

namespace gigascroll {

// One build thread: the room has a few hundred quads, and building on the calling thread
// keeps the BVH free of races visible to ThreadSanitizer.
ExhibitionScene::ExhibitionScene() : device_("threads=1") {
    scene_ = rtcNewScene(device_.handle());
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    // Watertight intersection: without it rays through a quad's diagonal slip between its
    // two triangles (a hole through boxes, and through the painting's centre line).
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
}

ExhibitionScene::~ExhibitionScene() {
    if (scene_) rtcReleaseScene(scene_);
}

void ExhibitionScene::require_open() const {
    require(!committed_, "the exhibition scene is already committed; build a new one to change it");
}

unsigned ExhibitionScene::add_quads(const std::vector<Vec3d>& vertices, std::size_t quads) {
    // Bounded extents keep the feedback pass's rays within Embree's range.
    for (const Vec3d& v : vertices) require_coordinate(v, "exhibition scene: a corner of a painting or box");
    RTCGeometry geom = rtcNewGeometry(device_.handle(), RTC_GEOMETRY_TYPE_QUAD);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        v[3 * i] = static_cast<float>(vertices[i].x);
        v[3 * i + 1] = static_cast<float>(vertices[i].y);
        v[3 * i + 2] = static_cast<float>(vertices[i].z);
    }
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), quads));
    for (std::size_t i = 0; i < 4 * quads; ++i) idx[i] = static_cast<unsigned>(i);
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    device_.check("the scene geometry");
    if (geom_placement_.size() <= id) geom_placement_.resize(id + 1, -1);
    return id;
}

std::size_t ExhibitionScene::add_painting(std::uint32_t painting, const PaintingGeometry& tiles,
                                          Vec3d origin, Vec3d u_axis, Vec3d v_axis, double width_m,
                                          double height_m) {
    require_open();
    require(painting < kMaxPaintings, "painting id out of range");
    require(tiles.fits_request_key(), "painting too large: more than 65536 tiles per axis");
    require(is_finite(origin) && is_finite(u_axis) && is_finite(v_axis),
            "painting placement has a non-finite coordinate");
    require(std::isfinite(width_m) && std::isfinite(height_m) && width_m > 0 && height_m > 0,
            "painting size must be positive and finite");
    require(std::abs(length(u_axis) - 1) < 1e-6 && std::abs(length(v_axis) - 1) < 1e-6 &&
                std::abs(dot(u_axis, v_axis)) < 1e-6,
            "painting u_axis and v_axis must be orthonormal");
    const Vec3d a = origin, b = origin + width_m * u_axis, c = b + height_m * v_axis,
               d = origin + height_m * v_axis;
    const unsigned id = add_quads({a, b, c, d}, 1);
    geom_placement_[id] = static_cast<int>(paintings_.size());
    paintings_.push_back({painting, tiles, origin, u_axis, v_axis, width_m, height_m});
    return paintings_.size() - 1;
}

void ExhibitionScene::add_box(Vec3d lo, Vec3d hi) {
    require_open();
    require(is_finite(lo) && is_finite(hi), "box has a non-finite coordinate");
    require(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z, "box needs lo < hi on every axis");
    auto p = [&](int i) {  // corner i: bit 0 -> x, bit 1 -> y, bit 2 -> z
        return Vec3d{i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z};
    };
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    std::vector<Vec3d> v;
    for (const auto& f : faces)
        for (int i : f) v.push_back(p(i));
    add_quads(v, 6);
    ++boxes_;
}

void ExhibitionScene::add_table(double x, double z, double length, double depth, double height) {
    require(length > 0.2 && depth > 0.2 && height > 0.05,
            "table needs length and depth > 0.2 m and height > 0.05 m");
    const double top = 0.04, leg = 0.06, hl = length / 2, hd = depth / 2;
    add_box({x - hl, height - top, z - hd}, {x + hl, height, z + hd});
    for (int sx : {-1, 1})
        for (int sz : {-1, 1}) {
            const double cx = x + sx * (hl - leg), cz = z + sz * (hd - leg);
            add_box({cx - leg / 2, 0, cz - leg / 2}, {cx + leg / 2, height - top, cz + leg / 2});
        }
}

void ExhibitionScene::commit() {
    require_open();
    rtcCommitScene(scene_);
    device_.check("the scene build");
    committed_ = true;
}

}  // namespace gigascroll

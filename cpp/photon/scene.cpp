#include "photon/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "common/limits.h"
#include "photon/rng.h"

namespace gigascroll {

namespace {
// Emitters are chosen by power; the mean of the RGB radiance is the per-area weight.
float emitter_weight(Vec3f le) { return (le.x + le.y + le.z) / 3.0f; }
}  // namespace

Scene::Scene() {
    scene_ = rtcNewScene(device_.handle());
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
}

Scene::~Scene() {
    if (scene_) rtcReleaseScene(scene_);
}

std::size_t Scene::add_mesh(const float* vertices, std::size_t nv, const std::int64_t* triangles,
                            std::size_t nt, const float* albedo, bool per_triangle, Vec3f emission) {
    require(!committed_, "Scene.add_mesh: the scene is already committed");
    require(nv > 0 && nt > 0, "Scene.add_mesh: a mesh needs at least one vertex and one triangle");
    require(nv <= 0xffffffffu && nt <= 0xffffffffu, "Scene.add_mesh: mesh too large (2^32 limit)");
    require(is_finite(emission) && emission.x >= 0 && emission.y >= 0 && emission.z >= 0,
            "Scene.add_mesh: emission must be finite and non-negative");
    // Bounded scene extents keep every hit point, and so every secondary ray, in Embree's range.
    for (std::size_t i = 0; i < 3 * nv; ++i)
        require(std::isfinite(vertices[i]) && std::abs(vertices[i]) <= kMaxCoordinate,
                "Scene.add_mesh: vertex " + std::to_string(i / 3) + " is not finite (NaN or Inf) or beyond +-1e12 (got " +
                    std::to_string(vertices[i]) + ")");
    const std::size_t na = per_triangle ? nt : 1;
    for (std::size_t i = 0; i < 3 * na; ++i)
        require(std::isfinite(albedo[i]) && albedo[i] >= 0.0f && albedo[i] < 1.0f,
                "Scene.add_mesh: albedo must be in [0, 1) (a surface reflecting all light "
                "makes the light transport diverge); got " + std::to_string(albedo[i]));
    for (std::size_t i = 0; i < 3 * nt; ++i)
        require(triangles[i] >= 0 && std::size_t(triangles[i]) < nv,
                "Scene.add_mesh: triangle " + std::to_string(i / 3) + " has vertex index " +
                    std::to_string(triangles[i]) + " outside [0, " + std::to_string(nv) + ")");

    auto vert = [&](std::int64_t i) { return Vec3f(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]); };
    std::vector<std::uint32_t> kept;
    kept.reserve(nt);
    for (std::size_t t = 0; t < nt; ++t) {
        const Vec3f a = vert(triangles[3 * t]), b = vert(triangles[3 * t + 1]), c = vert(triangles[3 * t + 2]);
        const Vec3f ng = cross(b - a, c - a);
        const float len = length(ng);
        if (!(len > 0.0f) || !std::isfinite(len)) continue;  // degenerate: dropped
        kept.push_back(std::uint32_t(t));
    }
    if (kept.empty()) return 0;

    RTCGeometry geom = rtcNewGeometry(device_.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
    // rtcSetNewGeometryBuffer pads the buffer as Embree requires (16 bytes after the last vertex).
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                           RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
    auto* ib = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t), kept.size()));
    if (!vb || !ib) {
        rtcReleaseGeometry(geom);
        throw std::runtime_error("Embree: cannot allocate geometry buffers");
    }
    std::copy(vertices, vertices + 3 * nv, vb);
    const auto first = std::uint32_t(normal_.size());
    for (std::size_t k = 0; k < kept.size(); ++k) {
        const std::size_t t = kept[k];
        for (int j = 0; j < 3; ++j) ib[3 * k + j] = std::uint32_t(triangles[3 * t + j]);
        const Vec3f a = vert(triangles[3 * t]), b = vert(triangles[3 * t + 1]), c = vert(triangles[3 * t + 2]);
        normal_.push_back(normalize(cross(b - a, c - a)));
        const float* al = albedo + (per_triangle ? 3 * t : 0);
        albedo_.emplace_back(al[0], al[1], al[2]);
        emission_.push_back(emission);
        if (max_component(albedo_.back()) > 0) reflects_ = true;
        lo_ = vmin(lo_, vmin(a, vmin(b, c)));
        hi_ = vmax(hi_, vmax(a, vmax(b, c)));
    }
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    device_.check("the mesh");
    if (geom_offset_.size() <= id) geom_offset_.resize(id + 1), geom_vertices_.resize(id + 1);
    geom_offset_[id] = first;
    geom_vertices_[id] = nv;
    return kept.size();
}

void Scene::translate(Vec3f offset) {
    require(!committed_, "Scene.translate: the scene is already committed");
    require(is_finite(offset), "Scene.translate: the offset must be finite");
    for (unsigned g = 0; g < geom_offset_.size(); ++g) {
        RTCGeometry geom = rtcGetGeometry(scene_, g);
        auto* vb = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
        for (std::size_t i = 0; i < geom_vertices_[g]; ++i)
            vb[3 * i] += offset.x, vb[3 * i + 1] += offset.y, vb[3 * i + 2] += offset.z;
        rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(geom);
    }
    device_.check("the translation");
    if (!normal_.empty()) lo_ = lo_ + offset, hi_ = hi_ + offset;
}

void Scene::commit() {
    require(!committed_, "Scene.commit: already committed");
    require(!normal_.empty(), "Scene.commit: the scene is empty (add at least one non-degenerate mesh)");
    rtcCommitScene(scene_);
    device_.check("the scene build");
    eps_ = std::max(diagonal(), 1e-30f) * 1e-5f;
    // Emitter distribution: geometry is re-read from Embree's buffers.
    double total = 0;
    for (unsigned g = 0; g < geom_offset_.size(); ++g) {
        RTCGeometry geom = rtcGetGeometry(scene_, g);
        const auto* vb = static_cast<const float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
        const auto* ib = static_cast<const std::uint32_t*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_INDEX, 0));
        const std::uint32_t begin = geom_offset_[g];
        const std::uint32_t end = g + 1 < geom_offset_.size() ? geom_offset_[g + 1] : std::uint32_t(normal_.size());
        for (std::uint32_t t = begin; t < end; ++t) {
            const Vec3f le = emission_[t];
            if (emitter_weight(le) <= 0) continue;
            const std::uint32_t* tri = ib + 3 * (t - begin);
            auto v = [&](int j) { return Vec3f(vb[3 * tri[j]], vb[3 * tri[j] + 1], vb[3 * tri[j] + 2]); };
            const Vec3f a = v(0), e1 = v(1) - a, e2 = v(2) - a;
            const float area = 0.5f * length(cross(e1, e2));
            emitters_.push_back(t);
            tri_v0_.push_back(a);
            tri_e1_.push_back(e1);
            tri_e2_.push_back(e2);
            total += double(area) * emitter_weight(le);
            emitter_cdf_.push_back(float(total));
            power_ += le * (float(M_PI) * area);
        }
    }
    weight_total_ = float(total);
    if (total > 0)
        for (float& c : emitter_cdf_) c = float(c / total);
    if (!emitters_.empty()) {
        std::size_t buckets = 1;
        while (buckets < 2 * emitters_.size() && buckets < (std::size_t(1) << 16)) buckets *= 2;
        emitter_guide_.resize(buckets + 1);
        for (std::size_t b = 0; b <= buckets; ++b)
            emitter_guide_[b] = std::uint32_t(
                std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), float(b) / float(buckets)) -
                emitter_cdf_.begin());
    }
    committed_ = true;
}

void Scene::require_committed() const {
    require(committed_, "Scene: call commit() before rendering or tracing");
}

namespace {
// Embree aborts the process (its ray.valid() assertion) on a ray with a NaN, infinite or
// larger than ~1.8e18 component. Rays of the core start at bounded cameras and scenes, so
// this only fails for a bug or a caller's own ray: a ValueError then, never an abort.
// The message out of line and cold, the test inline and without branches: it runs before
// every ray (3% of a fine bake as a call).
[[gnu::noinline, gnu::cold]] void throw_invalid_ray(Vec3f o, Vec3f d) {
    throw InvalidArgument("ray origin and direction must be finite and within +-1e18, the direction "
                              "non-zero (got origin (" + std::to_string(o.x) + ", " + std::to_string(o.y) +
                              ", " + std::to_string(o.z) + "), direction (" + std::to_string(d.x) + ", " +
                              std::to_string(d.y) + ", " + std::to_string(d.z) + "))");
}
inline void require_valid_ray(Vec3f o, Vec3f d, float tfar) {
    constexpr float kLimit = 1e18f;
    const bool ok = (std::abs(o.x) <= kLimit) & (std::abs(o.y) <= kLimit) & (std::abs(o.z) <= kLimit) &
                    (std::abs(d.x) <= kLimit) & (std::abs(d.y) <= kLimit) & (std::abs(d.z) <= kLimit) &
                    (max_component(vabs(d)) > 0) & !std::isnan(tfar);
    if (!ok) [[unlikely]] throw_invalid_ray(o, d);
}
}  // namespace

bool Scene::intersect_checked(Vec3f o, Vec3f d, Hit& hit) const {
    require_committed();
    require_coordinate(Vec3d(o), "Scene.intersect: ray origin");
    require(is_finite(d) && max_component(vabs(d)) > 0 && max_component(vabs(d)) <= 1e12f,
            "Scene.intersect: ray direction must be finite, non-zero and within +-1e12");
    return intersect(o, d, hit);
}

bool Scene::intersect(Vec3f o, Vec3f d, Hit& hit, float tfar) const {
    return intersect_range(o, d, hit, 0.0f, tfar);
}

bool Scene::intersect_range(Vec3f o, Vec3f d, Hit& hit, float tnear, float tfar) const {
    require_valid_ray(o, d, tfar);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = o.x; rh.ray.org_y = o.y; rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x; rh.ray.dir_y = d.y; rh.ray.dir_z = d.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xffffffffu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar;
    hit.tri = geom_offset_[rh.hit.geomID] + rh.hit.primID;
    hit.p = o + d * hit.t;
    const Vec3f n = normal_[hit.tri];
    hit.front = dot(n, d) < 0;
    hit.n = hit.front ? n : -n;
    return true;
}

bool Scene::occluded(Vec3f o, Vec3f d, float tfar) const {
    require_valid_ray(o, d, tfar);
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray{};
    ray.org_x = o.x; ray.org_y = o.y; ray.org_z = o.z;
    ray.dir_x = d.x; ray.dir_y = d.y; ray.dir_z = d.z;
    ray.tnear = 0.0f;
    ray.tfar = tfar;
    ray.mask = 0xffffffffu;
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

void Scene::occluded16(int count, const Vec3f* o, const Vec3f* d, const float* tfar, bool* out) const {
    GS_CHECK(count >= 0 && count <= 16);
    if (count == 0) return;
    alignas(64) int valid[16];
    alignas(64) RTCRay16 ray;
    for (int k = 0; k < 16; ++k) {
        const int i = k < count ? k : 0;  // idle lanes repeat ray 0 (valid = 0: not traced)
        if (k < count) require_valid_ray(o[i], d[i], tfar[i]);
        valid[k] = k < count ? -1 : 0;
        ray.org_x[k] = o[i].x, ray.org_y[k] = o[i].y, ray.org_z[k] = o[i].z;
        ray.dir_x[k] = d[i].x, ray.dir_y[k] = d[i].y, ray.dir_z[k] = d[i].z;
        ray.tnear[k] = 0.0f, ray.tfar[k] = tfar[i], ray.time[k] = 0.0f;
        ray.mask[k] = 0xffffffffu, ray.id[k] = unsigned(k), ray.flags[k] = 0;
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded16(valid, scene_, &ctx, &ray);
    for (int k = 0; k < count; ++k) out[k] = ray.tfar[k] < 0.0f;
}

LightSample Scene::sample_emitter(float u_tri, float u1, float u2) const {
    LightSample s;
    if (emitters_.empty()) return s;
    std::size_t found;
    const std::size_t buckets = emitter_guide_.size() - 1;
    if (emitter_cdf_.size() <= 16) {
        // A few emitters (a room's lights): upper_bound's index is the number of entries that
        // u_tri is not below (the cdf is sorted; a NaN u counts them all, as upper_bound
        // returns the end for it), counted without branches.
        found = 0;
        for (const float c : emitter_cdf_) found += !(u_tri < c);
    } else if (u_tri >= 0.0f && u_tri < 1.0f) {
        // u * K is exact (K a power of two), so bucket b holds u: cdf entries before
        // guide[b] are <= b / K <= u, and the entry at guide[b + 1] is > (b + 1) / K > u.
        const auto b = std::min(std::size_t(u_tri * float(buckets)), buckets - 1);
        const float* lo = emitter_cdf_.data() + emitter_guide_[b];
        const float* hi = emitter_cdf_.data() + emitter_guide_[b + 1];
        found = std::size_t(std::upper_bound(lo, hi, u_tri) - emitter_cdf_.data());
    } else {
        found = std::size_t(std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u_tri) - emitter_cdf_.begin());
    }
    const std::size_t i = std::min<std::size_t>(found, emitters_.size() - 1);
    const std::uint32_t t = emitters_[i];
    // Fold the unit square onto the triangle, as selects (the photon pass's fold is a coin
    // flip for the branch predictor).
    const bool fold = u1 + u2 > 1.0f;
    u1 = fold ? 1.0f - u1 : u1;
    u2 = fold ? 1.0f - u2 : u2;
    s.tri = t;
    s.p = tri_v0_[i] + tri_e1_[i] * u1 + tri_e2_[i] * u2;
    s.n = normal_[t];
    s.radiance = emission_[t];
    // pdf_area = (w_i / W) / area_i and w_i = area_i * weight(Le): the area cancels.
    s.pdf_area = emitter_weight(s.radiance) / weight_total_;
    return s;
}

std::uint64_t Scene::position_key(Vec3f p) const {
    const Vec3f ext = vmax(hi_ - lo_, Vec3f(1e-30f, 1e-30f, 1e-30f));
    std::uint64_t key = 0x6a09e667f3bcc909ULL;
    for (int a = 0; a < 3; ++a) {
        // Walls often lie exactly on the bounds (u = 0 or 1): the non-dyadic shift keeps them
        // off bin boundaries, where rounding at another scale or from another eye would flip
        // the bin. 2^14 bins: coarse enough that rounding rarely crosses one, fine enough
        // that neighbouring pixels' hit points fall in different bins.
        const float u = std::clamp((p[a] - lo_[a]) / ext[a], 0.0f, 1.0f) * 0.6f + 0.2f;
        key = hash_combine(key, std::uint64_t(u * float(1 << 14)));
    }
    return key;
}

}  // namespace gigascroll

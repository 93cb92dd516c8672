#include "gallery/gallery.h"
#include "gallery/bake_job.h"
#include "gallery/hot_lattice.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <unordered_map>

#include "common/timing.h"
#include "common/error.h"
#include "common/parallel.h"
#include "photon/gather.h"
#include "photon/polygon_irradiance.h"
#include "photon/rng.h"
#include "pack/tile_key.h"
#include "sampling/sampler.h"
#include "views/feedback.h"

namespace gigascroll {

namespace {

// A painting's albedo where photons bounce off it, read once per lighting through the virtual
// texture at the painting's finest pinned level: the pinned tail (cache/page_table.h) is
// resident whatever the camera has streamed, so the photon map does not depend on the view
// history, and its texels (a few centimetres on a metre-sized painting) are already finer than
// the gather radius, which blurs anything finer away. Coarser still while its texels stay
// within an eighth of the gather radius (few photons, wide gathers: the read was most of a
// small light()). Bilinear between the level's texels. A new lighting takes the previous one's
// image of a painting when it reads the same level of the same pack in the same texel format
// (the pinned tiles are the pack's, whatever the cache): a light() with few photons spent a
// third of its time re-reading identical texels.
class PaintingAlbedo final : public AlbedoTexture {
public:
    struct Image {
        std::uint32_t width = 0, height = 0, level = 0;
        std::vector<Vec3f> texels;
    };
    PaintingAlbedo(const std::vector<PaintingPlacement>& placements, const std::vector<int>& tri_slot,
                   const VirtualTexture& vt, double gather_radius, PaintingAlbedo* previous)
        : placements_(placements), tri_slot_(tri_slot), pack_fingerprint_(vt.pack_fingerprint()),
          format_(vt.format()) {
        // Only a cache that remembers its pack identifies the texels (0: built from a layout).
        if (previous && (pack_fingerprint_ == 0 || previous->pack_fingerprint_ != pack_fingerprint_ ||
                         previous->format_ != format_ || previous->images_.size() != placements.size()))
            previous = nullptr;
        for (const PaintingPlacement& p : placements) {
            const PaintingGeometry& g = p.tiles;
            std::uint32_t level = g.levels() - 1;
            for (std::uint32_t l = 0; l < g.levels(); ++l)
                if (vt.is_pinned(TileKey{p.painting, l, 0, 0})) {
                    level = l;
                    break;
                }
            // A bound on memory for packs whose tail starts fine (a pinned level of a
            // megatexel is more than the gather can use).
            while (level + 1 < g.levels() &&
                   std::uint64_t(g.level_width(level)) * g.level_height(level) > (1u << 20))
                ++level;
            auto texel_m = [&](std::uint32_t l) {
                return std::max(p.width_m / g.level_width(l), p.height_m / g.level_height(l));
            };
            while (level + 1 < g.levels() && texel_m(level + 1) <= gather_radius / 8) ++level;
            if (previous) {
                Image& old = previous->images_[images_.size()];
                if (old.level == level && old.width == g.level_width(level) && old.height == g.level_height(level) &&
                    old.texels.size() == std::size_t(old.width) * old.height && !old.texels.empty()) {
                    images_.push_back(std::move(old));
                    continue;
                }
            }
            Image im;
            im.level = level;
            im.width = g.level_width(level), im.height = g.level_height(level);
            const std::size_t n = std::size_t(im.width) * im.height;
            std::vector<double> u(n), v(n);
            for (std::uint32_t y = 0; y < im.height; ++y)
                for (std::uint32_t x = 0; x < im.width; ++x) {
                    u[y * std::size_t(im.width) + x] = (x + 0.5) / im.width;
                    v[y * std::size_t(im.width) + x] = (y + 0.5) / im.height;
                }
            std::vector<float> rgb(3 * n);
            SampleRequest r;
            r.painting = p.painting;
            r.u = u.data(), r.v = v.data();
            r.lod_scalar = float(level);
            r.count = n;
            r.filter = Filter::Bilinear;
            r.out = rgb.data();
            sample_serial(vt, r);
            im.texels.resize(n);
            for (std::size_t i = 0; i < n; ++i)
                im.texels[i] = Vec3f(srgb_code_table(rgb[3 * i]), srgb_code_table(rgb[3 * i + 1]), srgb_code_table(rgb[3 * i + 2])) *
                               kPaintingReflectance;
            images_.push_back(std::move(im));
        }
    }

    Vec3f albedo(std::uint32_t tri, Vec3f p, Vec3f constant) const override {
        const int s = tri < tri_slot_.size() ? tri_slot_[tri] : -1;
        if (s < 0) return constant;
        const PaintingPlacement& pl = placements_[s];
        const Image& im = images_[s];
        const Vec3d rel = Vec3d(p) - pl.origin;
        const double x = std::clamp(dot(rel, pl.u_axis) / pl.width_m, 0.0, 1.0) * im.width - 0.5;
        const double y = std::clamp(dot(rel, pl.v_axis) / pl.height_m, 0.0, 1.0) * im.height - 0.5;
        const double fx0 = std::floor(x), fy0 = std::floor(y);
        const float fx = float(x - fx0), fy = float(y - fy0);
        auto at = [&](double xi, double yi) {
            const auto cx = std::uint32_t(std::clamp(xi, 0.0, double(im.width - 1)));
            const auto cy = std::uint32_t(std::clamp(yi, 0.0, double(im.height - 1)));
            return im.texels[std::size_t(cy) * im.width + cx];
        };
        return (at(fx0, fy0) * (1 - fx) + at(fx0 + 1, fy0) * fx) * (1 - fy) +
               (at(fx0, fy0 + 1) * (1 - fx) + at(fx0 + 1, fy0 + 1) * fx) * fy;
    }

    const std::vector<Image>& images() const { return images_; }

private:
    const std::vector<PaintingPlacement>& placements_;
    const std::vector<int>& tri_slot_;
    std::uint64_t pack_fingerprint_;
    TexelFormat format_;
    std::vector<Image> images_;
};

// Photons on the wall behind a painting, in the gap between them: light trapped there is real
// but never seen, and a gather on the painting's face (its sphere reaches `depth` = the gather
// radius off the plane, far more than a 1 mm gap) would count it as light on the painting: the
// classic leak. A photon is dropped when it lies over or under a painting's rectangle, off its
// plane by less than `depth`, on a surface whose normal points back at the painting (the
// wall it hangs on, seen from the gap). Either side counts, so the rule does not depend on
// which way u x v points. The painting's own photons (on its plane) stay.
void drop_hidden_photons(std::vector<Photon>& photons, const std::vector<PaintingPlacement>& paintings,
                         float depth, unsigned threads) {
    if (paintings.empty()) return;
    // Each painting's box (its rectangle swept `depth` along the normal, padded well beyond
    // the rounding of the test below) rejects most photons in a few float compares; the
    // photons inside take the exact test, so the same photons are dropped.
    struct Box {
        Vec3f lo, hi;
        Vec3d n;
    };
    std::vector<Box> boxes;
    for (const PaintingPlacement& p : paintings) {
        const Vec3d n = p.normal();
        Vec3d lo(INFINITY, INFINITY, INFINITY), hi = -lo;
        for (int k = 0; k < 8; ++k) {
            const Vec3d c = p.origin + p.u_axis * (k & 1 ? p.width_m : 0.0) + p.v_axis * (k & 2 ? p.height_m : 0.0) +
                            n * (k & 4 ? double(depth) : -double(depth));
            lo = vmin(lo, c), hi = vmax(hi, c);
        }
        const double pad = 1e-3 * (p.width_m + p.height_m + double(depth)) +
                           1e-5 * max_component(vmax(vabs(lo), vabs(hi)));
        Box b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::nextafter(float(lo[a] - pad), -INFINITY);
            b.hi[a] = std::nextafter(float(hi[a] + pad), INFINITY);
        }
        b.n = n;
        boxes.push_back(b);
    }
    auto hidden = [&](const Photon& ph) {
        for (std::size_t i = 0; i < paintings.size(); ++i) {
            const Box& b = boxes[i];
            if (!(ph.p.x >= b.lo.x && ph.p.x <= b.hi.x && ph.p.y >= b.lo.y && ph.p.y <= b.hi.y &&
                  ph.p.z >= b.lo.z && ph.p.z <= b.hi.z))
                continue;
            const PaintingPlacement& p = paintings[i];
            const Vec3d n = b.n, rel = Vec3d(ph.p) - p.origin;
            const double h = dot(rel, n);
            if (!(std::abs(h) < double(depth))) continue;  // first: most photons are far off the plane
            // On the plane within float rounding of a point at this distance from the origin.
            const double on_plane = 1e-5 * (length(rel) + p.width_m + p.height_m);
            if (!(std::abs(h) > on_plane)) continue;
            if (!(dot(Vec3d(ph.n), n) * (h > 0 ? 1.0 : -1.0) < -0.5)) continue;
            const double u = dot(rel, p.u_axis), v = dot(rel, p.v_axis);
            if (u >= 0 && u <= p.width_m && v >= 0 && v <= p.height_m) return true;
        }
        return false;
    };
    // The test on both cores, the (memory-bound) compaction in order on one.
    std::vector<std::uint8_t> drop(photons.size());
    parallel_for(photons.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) drop[i] = hidden(photons[i]);
    }, threads);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < photons.size(); ++i)
        if (!drop[i]) photons[kept++] = photons[i];
    photons.resize(kept);
}

// Normals are quantised to 1/256 per component: a photon's normal lies within
// sqrt(3) / 512 < 0.004 of its group's, so kGroupSlack covers the rounding.
constexpr float kNormalQuantum = 256.0f;
constexpr float kGroupSlack = 0.01f;
constexpr std::size_t kMaxPhotonGroups = 4096;

// Roberts' R2 sequence (the plastic number's additive recurrence): point i of any count is
// frac(shift + i alpha), well spread in the unit square, and so is every run of consecutive
// points (the samples that pick one emitter below).
constexpr double kPhi2 = 1.3247179572447460;
constexpr double kR2[2] = {1.0 / kPhi2, 1.0 / (kPhi2 * kPhi2)};

// Lattice point (i, j), i + j <= n, of a triangle with n segments per edge.
inline std::uint64_t lattice_index(std::uint32_t i, std::uint32_t j, std::uint32_t n) {
    return std::uint64_t(i) * (n + 1) - std::uint64_t(i) * (i - 1) / 2 + j;
}
inline std::uint64_t lattice_points(std::uint32_t n) { return std::uint64_t(n + 1) * (n + 2) / 2; }

}  // namespace

Lighting parse_lighting(const std::string& name) {
    if (name == "unlit") return Lighting::Unlit;
    if (name == "baked") return Lighting::Baked;
    if (name == "full") return Lighting::Full;
    throw InvalidArgument("lighting must be 'baked', 'full' or 'unlit', not '" + name + "'");
}

std::size_t Gallery::add_surface(const float* vertices, std::size_t nv, const std::int64_t* triangles,
                                 std::size_t nt, Vec3f albedo, Vec3f emission) {
    require(!committed(), "Gallery: already committed");
    require(is_finite(albedo) && albedo.x >= 0 && albedo.y >= 0 && albedo.z >= 0 && albedo.x < 1 &&
                albedo.y < 1 && albedo.z < 1,
            "Gallery: a surface's albedo must be in [0, 1) per channel");
    const float al[3] = {albedo.x, albedo.y, albedo.z};
    const std::size_t before = scene_.geometry_count();
    const std::size_t kept = scene_.add_mesh(vertices, nv, triangles, nt, al, false, emission);
    if (kept == 0) return 0;
    geom_first_tri_.push_back(std::uint32_t(tri_v0_.size()));
    // The same degeneracy test as Scene::add_mesh, so our copy lists the triangles it kept.
    auto vert = [&](std::int64_t i) {
        return Vec3f(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
    };
    for (std::size_t t = 0; t < nt; ++t) {
        const Vec3f a = vert(triangles[3 * t]), b = vert(triangles[3 * t + 1]),
                    c = vert(triangles[3 * t + 2]);
        const float len = length(cross(b - a, c - a));
        if (!(len > 0.0f) || !std::isfinite(len)) continue;
        tri_v0_.push_back(a), tri_e1_.push_back(b - a), tri_e2_.push_back(c - a);
        tri_slot_.push_back(-1);
    }
    GS_CHECK(tri_v0_.size() == scene_.triangle_count());
    GS_CHECK(scene_.geometry_count() == before + 1);
    geom_placement_.resize(scene_.geometry_count(), -1);
    return kept;
}

std::size_t Gallery::add_painting(std::uint32_t painting, const PaintingGeometry& tiles, Vec3d origin,
                                  Vec3d u_axis, Vec3d v_axis, double width_m, double height_m) {
    require(!committed(), "Gallery: already committed");
    require(painting < kMaxPaintings, "Gallery: painting id out of range");
    require(tiles.fits_request_key(), "Gallery: painting too large: more than 65536 tiles per axis");
    require(is_finite(origin) && is_finite(u_axis) && is_finite(v_axis),
            "Gallery: a painting placement has a non-finite coordinate");
    require(std::isfinite(width_m) && std::isfinite(height_m) && width_m > 0 && height_m > 0,
            "Gallery: painting size must be positive and finite");
    require(std::abs(length(u_axis) - 1) < 1e-6 && std::abs(length(v_axis) - 1) < 1e-6 &&
                std::abs(dot(u_axis, v_axis)) < 1e-6,
            "Gallery: painting u_axis and v_axis must be orthonormal");
    const Vec3d a = origin, b = origin + width_m * u_axis, c = b + height_m * v_axis,
                d = origin + height_m * v_axis;
    const float vertices[12] = {float(a.x), float(a.y), float(a.z), float(b.x), float(b.y), float(b.z),
                                float(c.x), float(c.y), float(c.z), float(d.x), float(d.y), float(d.z)};
    const std::int64_t triangles[6] = {0, 1, 2, 0, 2, 3};
    // The scene's own albedo of a painting is a placeholder that only says "it reflects": the
    // photon tracer reads PaintingAlbedo and the display pass the virtual texture.
    const std::size_t slot = placements_.size();
    const std::size_t kept = add_surface(vertices, 4, triangles, 2, Vec3f(0.5f, 0.5f, 0.5f), {0, 0, 0});
    require(kept == 2, "Gallery: a painting rectangle is too small to be represented in float");
    tri_slot_[tri_slot_.size() - 1] = tri_slot_[tri_slot_.size() - 2] = int(slot);
    geom_placement_.back() = int(slot);
    placements_.push_back({painting, tiles, origin, u_axis, v_axis, width_m, height_m});
    return slot;
}

namespace {
// Where a room is held (Gallery::origin): per axis, the middle of the room where the room lies
// on one side of the world's origin and its far side is at most twice as far as its near side,
// else 0. Then every vertex minus the middle is exact in float (Sterbenz's lemma), and a room
// around the origin keeps its coordinates (and so its frames) bit for bit. Far from the origin
// this restores float's precision where the light is computed: at 9 km a float's step is 1 mm,
// ten times the scene's ray offset (Scene::epsilon), which left shadow acne in stripes and a
// room 30 to 85% darker.
Vec3f room_origin(Vec3f lo, Vec3f hi) {
    Vec3f o(0, 0, 0);
    for (int k = 0; k < 3; ++k) {
        const float near = std::min(std::abs(lo[k]), std::abs(hi[k]));
        const float far = std::max(std::abs(lo[k]), std::abs(hi[k]));
        if ((lo[k] > 0) == (hi[k] > 0) && lo[k] != 0 && hi[k] != 0 && far <= 2 * near)
            o[k] = float(0.5 * (double(lo[k]) + double(hi[k])));
    }
    return o;
}
}  // namespace

std::pair<Vec3d, Vec3d> Gallery::bounds() const {
    return {Vec3d(scene_.bounds_min()) + origin_, Vec3d(scene_.bounds_max()) + origin_};
}

bool Gallery::intersect(Vec3d o, Vec3f d, Hit& hit) const {
    require(committed(), "Gallery.intersect: commit first");
    if (!scene_.intersect(Vec3f(o - origin_), d, hit)) return false;
    hit.p = Vec3f(Vec3d(hit.p) + origin_);
    return true;
}

void Gallery::commit() {
    require(!committed(), "Gallery: already committed");
    require(scene_.triangle_count() > 0, "Gallery: the room is empty");
    const Vec3f o = room_origin(scene_.bounds_min(), scene_.bounds_max());
    if (o.x != 0 || o.y != 0 || o.z != 0) {
        scene_.translate(-o);
        for (Vec3f& v0 : tri_v0_) v0 = v0 - o;  // as Embree's copy: exact, so e1 and e2 hold
        origin_ = Vec3d(o);
        for (PaintingPlacement& p : placements_) p.origin = p.origin - origin_;
    }
    scene_.commit();
    for (std::size_t t = 0; t < tri_v0_.size(); ++t)
        if (max_component(scene_.emission(t)) > 0) emitter_tris_.push_back(std::uint32_t(t));
    // Edges two emitter triangles share, in opposite directions, on one plane with one
    // radiance (a quad light's diagonal): unoccluded_irradiance leaves out their terms, which
    // cancel (unit_triangle_irradiance).
    emitter_shared_edges_.assign(emitter_tris_.size(), 0);
    {
        std::map<std::array<float, 6>, std::pair<std::size_t, int>> edges;
        for (std::size_t k = 0; k < emitter_tris_.size(); ++k) {
            const std::uint32_t t = emitter_tris_[k];
            const Vec3f v[3] = {tri_v0_[t], tri_v0_[t] + tri_e1_[t], tri_v0_[t] + tri_e2_[t]};
            for (int j = 0; j < 3; ++j) {
                const Vec3f from = v[j], to = v[(j + 1) % 3];
                const auto it = edges.find({to.x, to.y, to.z, from.x, from.y, from.z});
                if (it != edges.end()) {
                    const auto [other, oj] = it->second;
                    const std::uint32_t u = emitter_tris_[other];
                    const Vec3f le = scene_.emission(t), lo = scene_.emission(u);
                    const bool coplanar = dot(scene_.normal(t), scene_.normal(u)) > 1.0f - 1e-6f;
                    if (coplanar && le.x == lo.x && le.y == lo.y && le.z == lo.z &&
                        !(emitter_shared_edges_[other] >> oj & 1)) {
                        emitter_shared_edges_[k] |= 1u << j;
                        emitter_shared_edges_[other] |= 1u << oj;
                        edges.erase(it);
                        continue;
                    }
                }
                edges.emplace(std::array<float, 6>{from.x, from.y, from.z, to.x, to.y, to.z}, std::pair{k, j});
            }
        }
    }
    tri_terms_.resize(tri_v0_.size());
    for (std::size_t t = 0; t < tri_v0_.size(); ++t) {
        const Vec3f e1 = tri_e1_[t], e2 = tri_e2_[t];
        BarycentricTerms& b = tri_terms_[t];
        b.d00 = dot(e1, e1), b.d01 = dot(e1, e2), b.d11 = dot(e2, e2);
        b.denom = b.d00 * b.d11 - b.d01 * b.d01;
    }
}

PaintingSceneView Gallery::feedback_view() const {
    require(committed(), "Gallery: commit() before the feedback pass");
    return {scene_.handle(), placements_, geom_placement_, origin_};
}

void Gallery::check_texture(const VirtualTexture& vt) const {
    const auto& layout = vt.layout().paintings;
    // The messages only when they are thrown: this runs in every light() and display call.
    for (const PaintingPlacement& p : placements_) {
        if (p.painting >= layout.size())
            throw InvalidArgument("Gallery: painting " + std::to_string(p.painting) +
                                  " is not in the virtual texture's pack");
        const PaintingGeometry& g = layout[p.painting];
        if (!(g.width() == p.tiles.width() && g.height() == p.tiles.height() && g.levels() == p.tiles.levels() &&
              g.payload() == p.tiles.payload()))
            throw InvalidArgument("Gallery: the virtual texture's painting " + std::to_string(p.painting) +
                                  " is not the one the gallery was built from");
    }
}

void Gallery::light(const VirtualTexture& vt, const LightingSettings& s) {
    require(committed(), "Gallery: commit() before light()");
    require(scene_.emitter_count() > 0, "Gallery: the room has no light (no surface emits)");
    require(s.photons > 0 && s.photons <= (1ull << 32), "Gallery: photons must be in [1, 2^32]");
    require(std::isfinite(s.radius) && s.radius >= 0, "Gallery: radius must be finite and >= 0");
    require(s.light_samples >= 1 && s.light_samples <= 1 << 16, "Gallery: light_samples must be in [1, 65536]");
    check_texture(vt);
    std::unique_lock lock(mutex_);
    lighting_ = s;
    float radius = s.radius;
    const float diag = scene_.diagonal();
    if (radius == 0) {
        double area = 0;
        for (std::size_t t = 0; t < tri_v0_.size(); ++t)
            area += 0.5 * double(length(cross(tri_e1_[t], tri_e2_[t])));
        radius = float(std::sqrt(100.0 * area / (M_PI * double(s.photons))));
        radius = std::clamp(radius, 1e-4f * diag, 0.05f * diag);
    }
    renderer_.reset();
    // The previous map's storage is recycled by the new one (fresh pages were a sixth of a
    // 2^20-photon light()).
    std::unique_ptr<PhotonMap> retired = std::move(map_);
    bake_n_.clear(), bake_offset_.clear(), bake_front_.clear(), bake_back_.clear();
    scene_.set_albedo_texture(nullptr);
    auto albedo = std::make_unique<PaintingAlbedo>(placements_, tri_slot_, vt, radius,
                                                   dynamic_cast<PaintingAlbedo*>(albedo_.get()));
    stats_ = {};
    for (const auto& im : albedo->images()) stats_.albedo_levels.push_back(im.level);
    scene_.set_albedo_texture(albedo.get());
    albedo_ = std::move(albedo);
    // The renderer does direct light only; the photon map is the gallery's own, so that the
    // photons in the gap behind each painting can be dropped first (drop_hidden_photons).
    RenderSettings rs;
    rs.photons = s.photons;
    rs.gather.radius = radius;
    rs.light_samples = s.light_samples;
    rs.seed = s.seed;
    rs.threads = s.threads;
    rs.indirect = false;
    renderer_ = std::make_unique<Renderer>(scene_, rs);
    auto t0 = Clock::now();
    std::vector<Photon>& photons = photon_scratch_;  // its capacity kept from the last light()
    if (s.indirect) trace_photons(photons, scene_, s.photons, s.seed, s.threads);
    else photons.clear();  // direct light only: no photons, no map
    stats_.photon_seconds = seconds_since(t0);
    t0 = Clock::now();
    drop_hidden_photons(photons, placements_, radius, s.threads);
    gather_.radius = radius;
    // The adaptive grid (the renders' default): its queries walk only the cell rows their
    // sphere touches, over structure-of-arrays copies, and both passes of the surface disc's
    // gather are vectorised on it (the bake's disc gathers were most of the fine end's time
    // on VR-photon-mapping's 27 cells). Its build sorts on both cores (the same grid as a serial
    // build), beside the photon groups for the bake's skip_unlit. Below a few thousand
    // photons both take microseconds, less than handing one to the helper and waiting for it
    // (2^8 photons: 27 against 39 us), so they run in turn.
    parallel_for(2, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t job = b; job < e; ++job) {
            if (job == 0 && !photons.empty())
                map_ = std::make_unique<PhotonMap>(photons, radius, GridKind::Adaptive, HashGrid::Mode::Auto,
                                                   retired.get(), s.threads);
            else if (job == 1) group_photons(photons);
        }
    }, photons.size() < 4096 ? 1u : s.threads);
    retired.reset();
    stats_.build_seconds = seconds_since(t0);
    stats_.photons_stored = photons.size();
    // The scratch is kept for the next lighting unless it is large (beyond 2^22 photons,
    // 144 MiB, the memory matters more than the pages' faults).
    if (photons.capacity() > (std::size_t(1) << 22)) std::vector<Photon>().swap(photons);
    stats_.radius = radius;
}

void Gallery::group_photons(const std::vector<Photon>& photons) {
    photon_groups_.clear();
    photon_groups_overflow_ = false;
    std::unordered_map<std::uint64_t, std::size_t> index;
    for (const Photon& ph : photons) {
        std::uint64_t key = 0;
        for (int a = 0; a < 3; ++a)
            key = key << 16 | std::uint64_t(std::int64_t(std::floor(ph.n[a] * kNormalQuantum + 0.5f)) & 0xffff);
        auto [it, inserted] = index.try_emplace(key, photon_groups_.size());
        if (inserted) {
            if (photon_groups_.size() == kMaxPhotonGroups) {
                photon_groups_.clear();
                photon_groups_overflow_ = true;
                return;
            }
            photon_groups_.push_back({ph.n, ph.p, ph.p});
        }
        PhotonGroup& g = photon_groups_[it->second];
        g.lo = vmin(g.lo, ph.p), g.hi = vmax(g.hi, ph.p);
    }
}

bool Gallery::side_reachable(std::uint32_t t, Vec3f n) const {
    const float tol = 4 * scene_.epsilon();  // well above float rounding of plane distances
    const Vec3f v[3] = {tri_v0_[t], tri_v0_[t] + tri_e1_[t], tri_v0_[t] + tri_e2_[t]};
    // Direct light: Renderer::direct_irradiance counts a sample only when the emitter point
    // lies in front of the side (cos_x > 0) and the side's point in front of the emitter
    // (cos_l > 0). Both are linear in the points, so the triangles' vertices decide.
    for (const std::uint32_t e : emitter_tris_) {
        const Vec3f ev[3] = {tri_v0_[e], tri_v0_[e] + tri_e1_[e], tri_v0_[e] + tri_e2_[e]};
        const Vec3f ne = scene_.normal(e);
        float in_front = -std::numeric_limits<float>::infinity(), facing = in_front;
        for (int k = 0; k < 3; ++k) {
            in_front = std::max(in_front, dot(n, ev[k] - v[0]));
            facing = std::max(facing, dot(ne, v[k] - ev[0]));
        }
        if (in_front > tol && facing > tol) return true;
    }
    // Indirect light: the gather (sphere or disc) counts photons within the radius whose
    // normals agree with n (gather.h, surface_disc.h).
    if (photon_groups_overflow_) return true;
    const float r = gather_.radius + tol;
    const Vec3f lo = vmin(vmin(v[0], v[1]), v[2]) - Vec3f(r, r, r);
    const Vec3f hi = vmax(vmax(v[0], v[1]), v[2]) + Vec3f(r, r, r);
    for (const PhotonGroup& g : photon_groups_) {
        if (!(dot(g.n, n) > kNormalAgreement - kGroupSlack)) continue;
        if (g.lo.x <= hi.x && g.hi.x >= lo.x && g.lo.y <= hi.y && g.hi.y >= lo.y && g.lo.z <= hi.z &&
            g.hi.z >= lo.z)
            return true;
    }
    return false;
}

Vec3f Gallery::unoccluded_irradiance(Vec3f p, Vec3f n) const {
    Vec3f E{0, 0, 0};
    for (std::size_t k = 0; k < emitter_tris_.size(); ++k) {
        const std::uint32_t e = emitter_tris_[k];
        const Vec3f a = tri_v0_[e];
        const float u = unit_triangle_irradiance(p, n, a, a + tri_e1_[e], a + tri_e2_[e], emitter_shared_edges_[k]);
        if (u != 0) E += scene_.emission(e) * u;
    }
    return vmax(E, Vec3f(0, 0, 0));  // the parts' sum is >= 0 up to rounding
}

Vec3f Gallery::direct_stratified(const Hit& hit, int samples, ShadeCounters& c, int analytic_probes) const {
    if (scene_.emitter_count() == 0 || samples <= 0) return {0, 0, 0};
    // Keyed by position like Renderer::direct_irradiance, on its own stream.
    Rng rng(lighting_.seed, stream_id(StreamKind::Light, 0, 1), scene_.position_key(hit.p));
    const double shift[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
    auto sample = [&](int i) {
        // The emitter choice stratified in `samples` strata (one jittered lattice: emitter
        // triangles get their share of samples, in order), the point on it from R2. Every
        // coordinate is uniform on [0, 1) for a uniform shift: unbiased.
        float u[3];
        u[0] = std::min(float((double(i) + shift[0]) / double(samples)), 0x1.fffffep-1f);
        for (int a = 1; a < 3; ++a) {
            const double x = shift[a] + double(i) * kR2[a - 1];
            u[a] = float(x - std::floor(x));
        }
        // Onto the triangle by the square-root map (continuous, area-preserving: the points
        // stay as well spread as in the square), not by folding the square's upper half.
        const float su = std::sqrt(u[1]);
        return scene_.sample_emitter(u[0], 1.0f - su, u[2] * su);
    };
    Vec3f E{0, 0, 0};
    if (analytic_probes < 0) {
        for (int i = 0; i < samples; ++i) E += emitter_sample_irradiance(scene_, hit, sample(i), c);
        return E * (1.0f / float(samples));
    }
    // BakeSettings::analytic_direct: emitter_sample_irradiance's terms with the unoccluded
    // contribution kept apart. The probes first (samples 0, step, 2 step, ...: one per group
    // of strata, so spread over the emitters); when they all reach a light, or none does,
    // the point is taken to see all of it or none, and the other samples are not drawn.
    Vec3f unoccluded{0, 0, 0};
    // At least half the samples: as they grow, only points that see all or none of the light
    // agree (the estimator stays consistent).
    const int probes = analytic_probes > 0 ? std::min(std::max(analytic_probes, samples / 2), samples) : 0;
    const int step = probes > 0 ? samples / probes : 1;
    int tested = 0, visible = 0;
    // Samples in batches of up to 16 whose shadow rays go out as one packet; the sums in
    // sample order.
    auto shade = [&](const int* index, int count) {
        Vec3f f[16], o[16], d[16];
        float tfar[16] = {};  // lanes past `rays` are masked off
        int ray_of[16];
        int rays = 0;
        for (int k = 0; k < count; ++k) {
            ray_of[k] = -1;
            EmitterShadowRay ray;
            if (!emitter_sample_unshadowed(scene_, hit, sample(index[k]), c, ray)) continue;
            f[k] = ray.contribution;
            o[rays] = ray.origin, d[rays] = ray.direction, tfar[rays] = ray.tfar;
            ray_of[k] = rays++;
        }
        bool blocked[16];
        scene_.occluded16(rays, o, d, tfar, blocked);
        for (int k = 0; k < count; ++k) {
            if (ray_of[k] < 0) continue;
            unoccluded += f[k];
            ++tested;
            if (!blocked[ray_of[k]]) E += f[k], ++visible;
        }
    };
    // Batches of 16 without a heap allocation per point: the probes, then the others.
    int batch[16], in_batch = 0;
    auto add = [&](int i) {
        batch[in_batch++] = i;
        if (in_batch == 16) shade(batch, in_batch), in_batch = 0;
    };
    auto flush = [&] {
        if (in_batch) shade(batch, in_batch), in_batch = 0;
    };
    for (int k = 0; k < probes; ++k) add(k * step);
    flush();
    const bool agreed = probes > 0 && probes < samples && tested == probes && (visible == 0 || visible == tested);
    if (!agreed) {
        for (int i = 0; i < samples; ++i)
            if (probes == 0 || i % step != 0 || i / step >= probes) add(i);
        flush();
    }
    // The ratio estimator: the exact unoccluded irradiance times the fraction of the drawn
    // samples' unoccluded sum that is visible, per channel; their plain mean where none
    // reached a light (nothing to say about visibility) or the formula has no value.
    if (visible == 0) return {0, 0, 0};  // what the ratio (or the mean) gives: no formula needed
    const Vec3f exact = unoccluded_irradiance(hit.p, hit.n);
    const int drawn = agreed ? probes : samples;
    for (int a = 0; a < 3; ++a) {
        const float r = E[a] / unoccluded[a];
        E[a] = unoccluded[a] > 0 && std::isfinite(exact[a]) && std::isfinite(r) ? exact[a] * std::min(r, 1.0f)
                                                                                : E[a] / float(drawn);
    }
    return E;
}

void Gallery::require_lit() const {
    require(renderer_ != nullptr, "Gallery: call light() before rendering with lighting");
}

Vec3f Gallery::irradiance_full(const Hit& hit) const {
    ShadeCounters c;
    KnnHeap heap;
    Vec3f E = renderer_->direct_irradiance(hit, lighting_.light_samples, c);
    return E + indirect(hit.p, hit.n, heap);
}

Vec3f Gallery::indirect(Vec3f p, Vec3f n, KnnHeap& heap, SurfaceDisc::Detail detail) const {
    if (!map_) return {0, 0, 0};
    if (!lighting_.disc) return map_->gather(p, n, gather_, heap);
    const DiscEstimate e = map_->gather_surface_disc(scene_, p, n, gather_.radius, detail);
    // A disc clipped to (almost) nothing carries no usable estimate (as the Renderer does).
    if (!(e.area > 1e-3f * float(M_PI) * gather_.radius * gather_.radius)) return {0, 0, 0};
    return e.power * (1.0f / e.area);
}

Vec3f Gallery::barycentric(std::uint32_t tri, Vec3f p) const {
    const Vec3f d = p - tri_v0_[tri], e1 = tri_e1_[tri], e2 = tri_e2_[tri];
    const auto [d00, d01, d11, denom] = tri_terms_[tri];
    const double d20 = dot(d, e1), d21 = dot(d, e2);
    double b1 = denom > 0 ? (d11 * d20 - d01 * d21) / denom : 0;
    double b2 = denom > 0 ? (d00 * d21 - d01 * d20) / denom : 0;
    b1 = std::clamp(b1, 0.0, 1.0), b2 = std::clamp(b2, 0.0, 1.0);
    if (b1 + b2 > 1) {
        const double s = b1 + b2;
        b1 /= s, b2 /= s;
    }
    return {float(b1), float(b2), 0};
}

Vec3f Gallery::irradiance_baked(const Hit& hit) const {
    const Vec3f b = barycentric(hit.tri, hit.p);
    return irradiance_baked_at(hit.tri, hit.front, b.x, b.y);
}

namespace {
// Linear interpolation on triangle t's lattice of n segments (points E) at barycentrics
// (b1, b2), clamped onto the triangle.
inline Vec3f lattice_lerp(const Vec3f* E, std::uint32_t n, float b1, float b2) {
    const LatticeCell cell = lattice_cell(std::int32_t(n), b1, b2);
    const auto i = std::uint32_t(cell.i), j = std::uint32_t(cell.j);
    const bool upper = cell.upper;
    // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i.
    const std::uint64_t row_i = lattice_index(i, 0, n), row_next = row_i + (n + 1 - i);
    const std::uint64_t right = row_next + j, up = row_i + j + 1;
    const std::uint64_t k0 = upper ? row_next + j + 1 : row_i + j;
    const std::uint64_t k1 = upper ? up : right, k2 = upper ? right : up;
    return E[k0] * cell.w0 + E[k1] * cell.w1 + E[k2] * cell.w2;
}
}  // namespace

Vec3f Gallery::irradiance_baked_at(std::uint32_t t, bool front, float b1, float b2) const {
    const std::vector<Vec3f>& side = front ? bake_front_ : bake_back_;
    return lattice_lerp(side.data() + bake_offset_[t], bake_n_[t], b1, b2);
}

namespace {
// lattice_lerp's float arithmetic for m <= 16 hits: the cell (i, j), the sub-triangle and
// the three weights.
struct LatticeCells {
    alignas(64) std::int32_t cell_i[16], cell_j[16], upper_of[16];
    alignas(64) float w0_of[16], w1_of[16], w2_of[16];
};
// No trapping math: with it GCC keeps the selects as branches (it will not evaluate a float
// compare or division unconditionally) and the loop scalar; no value changes. Out of line:
// the attribute keeps callees from inlining (Vec3f's operators were calls in it).
[[gnu::optimize("no-trapping-math"), gnu::noinline]]
void lattice_cells(std::size_t m, const std::uint32_t* __restrict segments,
                   const std::uint32_t* __restrict t_in, const float* __restrict b1_in,
                   const float* __restrict b2_in, LatticeCells& __restrict c) {
    std::int32_t* __restrict cell_i = c.cell_i;
    std::int32_t* __restrict cell_j = c.cell_j;
    std::int32_t* __restrict upper_of = c.upper_of;
    float* __restrict w0_of = c.w0_of;
    float* __restrict w1_of = c.w1_of;
    float* __restrict w2_of = c.w2_of;
    for (std::size_t k = 0; k < m; ++k) {
        const LatticeCell cell = lattice_cell(std::int32_t(segments[t_in[k]]), b1_in[k], b2_in[k]);
        cell_i[k] = cell.i, cell_j[k] = cell.j, upper_of[k] = cell.upper;
        w0_of[k] = cell.w0, w1_of[k] = cell.w1, w2_of[k] = cell.w2;
    }
}
}  // namespace

void Gallery::irradiance_baked_batch(const std::uint32_t* tri, const bool* front, const float* b1,
                                     const float* b2, std::size_t count, Vec3f* out) const {
    const Vec3f* front_E = bake_front_.data();
    const Vec3f* back_E = bake_back_.data();
    const std::uint32_t* segments = bake_n_.data();
    // lattice_lerp in two passes per 16 hits: its float arithmetic (the clamps, the cell, the
    // sub-triangle and weights) with selects in SIMD lanes, then per hit the lattice indices
    // (64-bit) and the blend: the same operations, so the same values.
    LatticeCells cells;
    for (std::size_t k0 = 0; k0 < count; k0 += 16) {
        const std::size_t m = std::min<std::size_t>(16, count - k0);
        const std::uint32_t* t_in = tri + k0;
        lattice_cells(m, segments, t_in, b1 + k0, b2 + k0, cells);
        for (std::size_t k = 0; k < m; ++k) {
            const std::uint32_t t = t_in[k], n = segments[t];
            const Vec3f* E = (front[k0 + k] ? front_E : back_E) + bake_offset_[t];
            const auto i = std::uint32_t(cells.cell_i[k]), j = std::uint32_t(cells.cell_j[k]);
            const bool upper = cells.upper_of[k];
            const std::uint64_t row_i = lattice_index(i, 0, n), row_next = row_i + (n + 1 - i);
            const std::uint64_t right = row_next + j, up = row_i + j + 1;
            const std::uint64_t e0 = upper ? row_next + j + 1 : row_i + j;
            const std::uint64_t e1 = upper ? up : right, e2 = upper ? right : up;
            out[k0 + k] = E[e0] * cells.w0_of[k] + E[e1] * cells.w1_of[k] + E[e2] * cells.w2_of[k];
        }
    }
}

namespace {
// BakeSettings::fill_covered's test: every one of nine probe rays from p (along the normal n,
// and eight at 60 degrees around it) meets a surface within `reach`. The ray along the
// normal goes first: on open surfaces (nearly every point) it is the only one.
bool covered_point(const Scene& scene, Vec3f p, Vec3f n, float reach) {
    const Vec3f o = p + n * scene.epsilon();
    if (!scene.occluded(o, n, reach)) return false;
    const Vec3f a = std::abs(n.x) > 0.5f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
    const Vec3f t = normalize(cross(n, a)), b = cross(n, t);
    constexpr float kCos = 0.5f, kSin = 0.8660254f;
    for (int k = 0; k < 8; ++k) {
        const float phi = float(k) * float(M_PI) / 4.0f;
        const Vec3f d = n * kCos + (t * std::cos(phi) + b * std::sin(phi)) * kSin;
        if (!scene.occluded(o, d, reach)) return false;
    }
    return true;
}

// Fills the covered points (mask, cleared as they are filled) of one side of one triangle's
// lattice of n segments, ring by ring: each gets the mean of its valid neighbours among the six
// of the triangular lattice. Points with no valid point anywhere on the lattice keep theirs.
void fill_covered_points(Vec3f* E, std::uint8_t* mask, std::uint32_t n) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> todo;
    for (std::uint32_t i = 0; i <= n; ++i)
        for (std::uint32_t j = 0; i + j <= n; ++j)
            if (mask[lattice_index(i, j, n)]) todo.emplace_back(i, j);
    static constexpr int kDi[6] = {1, -1, 0, 0, 1, -1}, kDj[6] = {0, 0, 1, -1, -1, 1};
    std::vector<std::pair<std::uint64_t, Vec3f>> ring;
    while (!todo.empty()) {
        ring.clear();
        std::size_t kept = 0;
        for (const auto [i, j] : todo) {
            Vec3f sum{0, 0, 0};
            int count = 0;
            for (int k = 0; k < 6; ++k) {
                const std::int64_t a = std::int64_t(i) + kDi[k], b = std::int64_t(j) + kDj[k];
                if (a < 0 || b < 0 || a + b > std::int64_t(n)) continue;
                const std::uint64_t q = lattice_index(std::uint32_t(a), std::uint32_t(b), n);
                if (!mask[q]) sum += E[q], ++count;
            }
            if (count) ring.emplace_back(lattice_index(i, j, n), sum * (1.0f / float(count)));
            else todo[kept++] = {i, j};
        }
        if (ring.empty()) return;  // nothing valid left to fill from
        for (const auto& [q, value] : ring) E[q] = value, mask[q] = 0;
        todo.resize(kept);
    }
}

// BakeSettings::indirect_filter on one side of one triangle's lattice of n segments (lattice
// steps a = e1 / n, b = e2 / n): each point's G replaced by the value at the point of the
// weighted least-squares plane through its neighbours' (Gaussian weights of standard
// deviation sigma metres, within 2.5 sigma, at most 8 steps each way; masked points left
// out). Where the fit is ill-posed (too few neighbours on a line), the weighted mean.
void filter_indirect(const Vec3f* G, const std::uint8_t* mask, std::uint32_t n, Vec3f a, Vec3f b, float sigma,
                     Vec3f* out) {
    const float cell = length(cross(a, b));
    const float reach = 2.5f * sigma;
    if (!(cell > 0) || !(sigma > 0)) {
        std::copy(G, G + lattice_points(n), out);
        return;
    }
    const int ki = std::min(8, int(std::ceil(reach * length(b) / cell)));
    const int kj = std::min(8, int(std::ceil(reach * length(a) / cell)));
    const float inv2s2 = 1.0f / (2 * sigma * sigma);
    for (std::uint32_t i = 0; i <= n; ++i)
        for (std::uint32_t j = 0; i + j <= n; ++j) {
            double m[6] = {0, 0, 0, 0, 0, 0};  // sum w [1 x y]^T [1 x y]: 00 01 02 11 12 22
            double r[3][3] = {};               // per channel: sum w v [1 x y]
            for (int di = -ki; di <= ki; ++di) {
                const std::int64_t ia = std::int64_t(i) + di;
                if (ia < 0 || ia > std::int64_t(n)) continue;
                for (int dj = -kj; dj <= kj; ++dj) {
                    const std::int64_t jb = std::int64_t(j) + dj;
                    if (jb < 0 || ia + jb > std::int64_t(n)) continue;
                    const Vec3f d = a * float(di) + b * float(dj);
                    const float d2 = dot(d, d);
                    if (d2 > reach * reach) continue;
                    const std::uint64_t q = lattice_index(std::uint32_t(ia), std::uint32_t(jb), n);
                    if (mask && mask[q]) continue;
                    const double w = std::exp(-d2 * inv2s2), x = di, y = dj;
                    m[0] += w, m[1] += w * x, m[2] += w * y, m[3] += w * x * x, m[4] += w * x * y, m[5] += w * y * y;
                    const float v[3] = {G[q].x, G[q].y, G[q].z};
                    for (int c = 0; c < 3; ++c) r[c][0] += w * v[c], r[c][1] += w * v[c] * x, r[c][2] += w * v[c] * y;
                }
            }
            const std::uint64_t k = lattice_index(i, j, n);
            if (!(m[0] > 0)) {
                out[k] = G[k];
                continue;
            }
            // The plane's value at (0, 0): Cramer's rule on the 3 x 3 normal equations.
            const double c00 = m[3] * m[5] - m[4] * m[4], c01 = m[2] * m[4] - m[1] * m[5], c02 = m[1] * m[4] - m[2] * m[3];
            const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
            // Well posed: the neighbours spread in both directions (det relative to m0^3 x var).
            const bool fit = det > 1e-3 * m[0] * m[0] * m[0];
            float v[3];
            for (int c = 0; c < 3; ++c)
                v[c] = float(fit ? (r[c][0] * c00 + r[c][1] * c01 + r[c][2] * c02) / det : r[c][0] / m[0]);
            // A fit never makes light negative (extrapolated at a lattice corner).
            out[k] = Vec3f(std::max(v[0], 0.0f), std::max(v[1], 0.0f), std::max(v[2], 0.0f));
        }
}
}  // namespace

Vec3f Gallery::final_gather(Vec3f p, Vec3f n, int rays, const std::vector<Vec3f>& front,
                            const std::vector<Vec3f>& back, const std::vector<std::uint32_t>& segments,
                            const std::vector<std::uint64_t>& offset) const {
    Rng rng(lighting_.seed, stream_id(StreamKind::Light, 0, 2), scene_.position_key(p));
    const Vec3f a = std::abs(n.x) > 0.5f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
    const Vec3f t = normalize(cross(n, a)), b = cross(n, t);
    const int m = int(std::lround(std::sqrt(double(rays))));
    const bool grid = m * m == rays;
    const Vec3f o = p + n * scene_.epsilon();
    Vec3f E{0, 0, 0};
    for (int k = 0; k < rays; ++k) {
        const double u1 = grid ? (double(k % m) + rng.uniform()) / m : rng.uniform();
        const double u2 = grid ? (double(k / m) + rng.uniform()) / m : rng.uniform();
        const float r = float(std::sqrt(u1)), phi = float(2 * M_PI * u2);
        const Vec3f d = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * float(std::sqrt(1 - u1));
        Hit h;
        if (!scene_.intersect(o, d, h)) continue;
        const Vec3f bc = barycentric(h.tri, h.p);
        const Vec3f E1 = lattice_lerp((h.front ? front : back).data() + offset[h.tri], segments[h.tri], bc.x, bc.y);
        // Cosine sampling: E = pi x mean radiance = mean(albedo x E1).
        E += scene_.albedo_at(h.tri, h.p) * E1;
    }
    return E * (1.0f / float(rays));
}

// Gallery::bake in steps (bake_job.h holds what they share), in the order they run:
// lattice layout, first pass (direct light and photon gathers), the gathers interpolated
// off their sub-lattice, the gathers added or filtered, covered points filled, the final
// gather, commit. Every step over the lattice rows advances bake_done_.
void Gallery::bake(const BakeSettings& s) {
    require(std::isfinite(s.spacing) && s.spacing >= 0, "Gallery.bake: spacing must be finite and >= 0");
    require(s.light_samples >= 1 && s.light_samples <= 1 << 16,
            "Gallery.bake: light_samples must be in [1, 65536]");
    require(s.shadow_probes >= 0 && s.shadow_probes <= 1 << 16, "Gallery.bake: shadow_probes must be in [0, 65536]");
    require(std::isfinite(s.indirect_filter) && s.indirect_filter >= 0 && s.indirect_filter <= 16,
            "Gallery.bake: indirect_filter must be in [0, 16] gather radii");
    require(s.final_gather >= 0 && s.final_gather <= 4096, "Gallery.bake: final_gather must be in [0, 4096] rays");
    const auto t0 = Clock::now();
    std::unique_lock lock(mutex_);
    require_lit();
    require(s.gather_stride == 1 || s.gather_stride == 2 || s.gather_stride == 4 || s.gather_stride == 8,
            "Gallery.bake: gather_stride must be 1, 2, 4 or 8");
    BakeJob job(s, lighting_.threads);
    bake_lattice_layout(job);
    bake_allocate(job);
    bake_first_pass(job);
    if (job.stride > 1) {
        if (job.separate)
            bake_interpolate(job, job.gather_front, job.gather_back, job.indirect_front, job.indirect_back, false);
        else
            bake_interpolate(job, job.gather_front, job.gather_back, job.front, job.back, true);
    }
    bake_add_indirect(job);
    bake_fill_covered(job);
    if (job.fg) bake_final_gather_pass(job);
    bake_commit(job);
    stats_.bake_seconds = seconds_since(t0);
}

// The lattice per triangle: n = ceil(longest edge / spacing) segments, rounded up to a
// multiple of gather_stride; offsets into the point arrays. Throws before anything changes.
void Gallery::bake_lattice_layout(BakeJob& job) const {
    const BakeSettings& s = job.s;
    const std::uint32_t stride = job.stride;
    job.spacing = s.spacing > 0 ? s.spacing : double(scene_.diagonal()) / 200.0;
    const std::size_t tris = job.tris = tri_v0_.size();
    // However coarse the spacing, a triangle has n >= gather_stride segments per edge.
    require(tris * lattice_points(stride) <= s.max_points,
            "Gallery.bake: " + std::to_string(tris) + " triangles are too many to bake: each needs at least " +
                std::to_string(lattice_points(stride)) + " lattice points and a bake holds at most " +
                std::to_string(s.max_points) + " (32 bytes each), so at most " +
                std::to_string(s.max_points / lattice_points(stride)) + " triangles");
    std::vector<std::uint32_t>& n = job.n;
    std::vector<std::uint64_t>& offset = job.offset;
    n.resize(tris);
    offset.assign(tris + 1, 0);
    for (std::size_t t = 0; t < tris; ++t) {
        const double l = std::max({double(length(tri_e1_[t])), double(length(tri_e2_[t])),
                                   double(length(tri_e2_[t] - tri_e1_[t]))});
        const double segments = std::ceil(l / job.spacing);
        require(segments < 65536, "Gallery.bake: spacing too fine for the room (more than 65535 "
                                  "lattice segments along a triangle edge)");
        n[t] = std::max(1u, std::uint32_t(segments));
        n[t] = (n[t] + stride - 1) / stride * stride;  // the gathers' sub-lattice: n / stride
        offset[t + 1] = offset[t] + lattice_points(n[t]);
        require(offset[t + 1] <= s.max_points,
                "Gallery.bake: spacing too fine: more than " + std::to_string(s.max_points) +
                    " lattice points");
    }
    job.total = offset[tris];
}

// The bake's arrays, work rows, reachable sides and edge insets; the gallery unbaked from
// here until bake_commit; the progress counters reset.
void Gallery::bake_allocate(BakeJob& job) {
    const BakeSettings& s = job.s;
    const std::size_t tris = job.tris;
    const std::uint32_t stride = job.stride;
    const std::uint64_t total = job.total;
    // On the previous bake's storage (its pages were a twentieth of a fine bake when fresh);
    // the gallery is unbaked until this bake completes.
    job.front = std::move(bake_front_), job.back = std::move(bake_back_);
    bake_n_.clear(), bake_offset_.clear(), bake_front_.clear(), bake_back_.clear();
    job.front.assign(total, Vec3f(0, 0, 0)), job.back.assign(total, Vec3f(0, 0, 0));
    // gather_stride s > 1: the gathers on the sub-lattice of the points whose i and j are
    // multiples of s (n / s segments), interpolated onto the others after the direct light.
    job.sub_offset.assign(tris + 1, 0);
    if (stride > 1)
        for (std::size_t t = 0; t < tris; ++t)
            job.sub_offset[t + 1] = job.sub_offset[t] + lattice_points(job.n[t] / stride);
    job.gather_front.resize(job.sub_offset[tris]), job.gather_back.resize(job.sub_offset[tris]);
    // Work items are lattice rows (triangle t, row i): a room is a few large triangles, so
    // splitting by triangle would leave one core with a whole wall.
    for (std::size_t t = 0; t < tris; ++t)
        for (std::uint32_t i = 0; i <= job.n[t]; ++i) job.rows.emplace_back(std::uint32_t(t), i);
    // Per triangle, bit 0 / 1: the front / back side can receive light.
    job.reachable.assign(tris, 3);
    if (s.skip_unlit)
        for (std::size_t t = 0; t < tris; ++t) {
            const Vec3f N = scene_.normal(std::uint32_t(t));
            job.reachable[t] = std::uint8_t(int(side_reachable(std::uint32_t(t), N)) |
                                            int(side_reachable(std::uint32_t(t), -N)) << 1);
            job.skipped += (job.reachable[t] & 1 ? 0 : 1) + (job.reachable[t] & 2 ? 0 : 1);
        }
    bake_done_ = 0;
    bake_total_ = job.rows.size() * ((stride > 1 ? 2 : 1) +
                                     (s.sparse_final_gather && stride > 1 && s.final_gather > 0 && map_ ? 1 : 0));
    // BakeSettings::inset_edges: a sixteenth of the triangle's lattice spacing, and clear of
    // float rounding at the scene's epsilon.
    job.inset.resize(tris);
    for (std::size_t t = 0; t < tris; ++t) {
        const float l = std::max({length(tri_e1_[t]), length(tri_e2_[t]), length(tri_e2_[t] - tri_e1_[t])});
        job.inset[t] = std::max(l / float(job.n[t]) / 16.0f, 32.0f * scene_.epsilon());
    }
    // BakeSettings::fill_covered: per point and side, whether it is covered.
    job.covered_front.resize(s.fill_covered ? total : 0), job.covered_back.resize(s.fill_covered ? total : 0);
    // BakeSettings::indirect_filter: the gathers kept apart from the direct light until filtered.
    job.filter = s.indirect_filter > 0 && map_ && gather_.radius > 0;
    job.fg = s.final_gather > 0 && map_;
    job.separate = job.filter || job.fg;  // the gathers apart from the direct light until the end
    job.sparse = s.sparse_final_gather && stride > 1;
    job.indirect_front.resize(job.separate ? total : 0), job.indirect_back.resize(job.separate ? total : 0);
}

// Lattice point (i, j) of triangle t; with inset_edges, a point on an edge moved toward the
// centroid (at most halfway): inside the triangle, off the neighbouring surfaces' planes.
Vec3f Gallery::bake_point(const BakeJob& job, std::uint32_t t, std::uint32_t i, std::uint32_t j) const {
    const std::uint32_t nt = job.n[t];
    Vec3f p = tri_v0_[t] + tri_e1_[t] * (float(i) / float(nt)) + tri_e2_[t] * (float(j) / float(nt));
    if (job.s.inset_edges && (i == 0 || j == 0 || i + j == nt)) {
        const Vec3f c = tri_v0_[t] + (tri_e1_[t] + tri_e2_[t]) * (1.0f / 3.0f);
        const float dc = length(c - p);
        if (dc > 0) p += (c - p) * std::min(0.5f, job.inset[t] / dc);
    }
    return p;
}

// The first pass, row by row: per point and reachable side, covered (flagged, its gather
// still taken on the sub-lattice) or the direct light, plus the photon gather (stride 1: at
// every point, added or kept apart; else on the sub-lattice only).
void Gallery::bake_first_pass(BakeJob& job) {
    const BakeSettings& s = job.s;
    const std::uint32_t stride = job.stride;
    const SurfaceDisc::Detail detail = s.coarse_disc ? SurfaceDisc::Detail::Coarse : SurfaceDisc::Detail::Fine;
    parallel_for(job.rows.size(), 4, [&](std::size_t rb, std::size_t re) {
        ShadeCounters c;
        KnnHeap heap;
        for (std::size_t r = rb; r < re; ++r) {
            const auto [t, i] = job.rows[r];
            const std::uint32_t nt = job.n[t];
            const Vec3f N = scene_.normal(t);
            if (!(max_component(scene_.albedo(t)) > 0)) continue;  // black either way
            for (std::uint32_t j = 0; i + j <= nt; ++j) {
                const std::uint64_t k = job.offset[t] + lattice_index(i, j, nt);
                Hit h;
                h.tri = t;
                h.p = bake_point(job, t, i, j);
                const bool on_sub = stride > 1 && i % stride == 0 && j % stride == 0;
                for (int side = 0; side < 2; ++side) {
                    if (!(job.reachable[t] >> side & 1)) continue;  // stays zero
                    h.front = side == 0;
                    h.n = h.front ? N : -N;
                    std::vector<Vec3f>& gather = h.front ? job.gather_front : job.gather_back;
                    const std::uint64_t q =
                        on_sub ? job.sub_offset[t] + lattice_index(i / stride, j / stride, nt / stride) : 0;
                    if (s.fill_covered && covered_point(scene_, h.p, h.n, 8.0f * job.inset[t])) {
                        (h.front ? job.covered_front : job.covered_back)[k] = 1;
                        // The gathers' sub-lattice interpolates onto uncovered points too.
                        if (on_sub) gather[q] = indirect(h.p, h.n, heap, detail);
                        continue;
                    }
                    Vec3f E = s.stratified ? direct_stratified(h, s.light_samples, c, s.analytic_direct ? s.shadow_probes : -1)
                                           : renderer_->direct_irradiance(h, s.light_samples, c);
                    if (stride == 1 && job.separate)
                        (h.front ? job.indirect_front : job.indirect_back)[k] = indirect(h.p, h.n, heap, detail);
                    else if (stride == 1) E += indirect(h.p, h.n, heap, detail);
                    else if (on_sub) gather[q] = indirect(h.p, h.n, heap, detail);
                    (h.front ? job.front : job.back)[k] = E;
                }
            }
        }
        bake_done_.fetch_add(re - rb, std::memory_order_relaxed);
    }, job.threads);
}

// The sub-lattice's values (sub_f, sub_b) interpolated onto every point of (out_f, out_b):
// added (add = true) or written. Linear on the sub-lattice's triangles, as irradiance_baked
// reads the lattice; i + j <= n keeps every corner with a non-zero weight on it.
void Gallery::bake_interpolate(BakeJob& job, const std::vector<Vec3f>& sub_f, const std::vector<Vec3f>& sub_b,
                               std::vector<Vec3f>& out_f, std::vector<Vec3f>& out_b, bool add) {
    const std::uint32_t stride = job.stride;
    parallel_for(job.rows.size(), 16, [&](std::size_t rb, std::size_t re) {
        for (std::size_t r = rb; r < re; ++r) {
            const auto [t, i] = job.rows[r];
            const std::uint32_t nt = job.n[t], m = nt / stride, a = i / stride;
            const float fx = float(i % stride) / float(stride);
            if (!(max_component(scene_.albedo(t)) > 0)) continue;
            for (int side = 0; side < 2; ++side) {
                if (!(job.reachable[t] >> side & 1)) continue;
                const Vec3f* G = (side == 0 ? sub_f : sub_b).data() + job.sub_offset[t];
                Vec3f* E = (side == 0 ? out_f : out_b).data() + job.offset[t];
                for (std::uint32_t j = 0; i + j <= nt; ++j) {
                    const std::uint32_t b = j / stride;
                    const float fy = float(j % stride) / float(stride);
                    Vec3f g = G[lattice_index(a, b, m)] * (1 - fx - fy);
                    if (fx + fy <= 1) {
                        if (fx > 0) g += G[lattice_index(a + 1, b, m)] * fx;
                        if (fy > 0) g += G[lattice_index(a, b + 1, m)] * fy;
                    } else {
                        g = G[lattice_index(a + 1, b + 1, m)] * (fx + fy - 1) +
                            G[lattice_index(a, b + 1, m)] * (1 - fx) + G[lattice_index(a + 1, b, m)] * (1 - fy);
                    }
                    if (add) E[lattice_index(i, j, nt)] += g;
                    else E[lattice_index(i, j, nt)] = g;
                }
            }
        }
        bake_done_.fetch_add(re - rb, std::memory_order_relaxed);
    }, job.threads);
}

// The gathers kept apart (separate) onto the first pass: added, or with indirect_filter
// smoothed per triangle first. With the final gather, the direct light is kept before.
void Gallery::bake_add_indirect(BakeJob& job) {
    const BakeSettings& s = job.s;
    if (job.fg) job.direct_front = job.front, job.direct_back = job.back;
    if (job.separate && !job.filter)
        for (std::uint64_t k = 0; k < job.total; ++k)
            job.front[k] += job.indirect_front[k], job.back[k] += job.indirect_back[k];
    if (!job.filter) return;
    parallel_for(job.tris, 1, [&](std::size_t tb, std::size_t te) {
        std::vector<Vec3f> smooth;
        for (std::size_t t = tb; t < te; ++t) {
            if (!(max_component(scene_.albedo(std::uint32_t(t))) > 0)) continue;
            const float inv_n = 1.0f / float(job.n[t]);
            smooth.resize(lattice_points(job.n[t]));
            for (int side = 0; side < 2; ++side) {
                if (!(job.reachable[t] >> side & 1)) continue;
                const Vec3f* G = (side == 0 ? job.indirect_front : job.indirect_back).data() + job.offset[t];
                const std::vector<std::uint8_t>& covered = side == 0 ? job.covered_front : job.covered_back;
                const std::uint8_t* mask = s.fill_covered ? covered.data() + job.offset[t] : nullptr;
                filter_indirect(G, mask, job.n[t], tri_e1_[t] * inv_n, tri_e2_[t] * inv_n,
                                s.indirect_filter * gather_.radius, smooth.data());
                Vec3f* E = (side == 0 ? job.front : job.back).data() + job.offset[t];
                for (std::size_t q = 0; q < smooth.size(); ++q) E[q] += smooth[q];
            }
        }
    }, job.threads);
}

// fill_covered: the covered point sides counted, their masks kept for the final gather, and
// the first pass's covered points filled from their uncovered neighbours.
void Gallery::bake_fill_covered(BakeJob& job) {
    if (!job.s.fill_covered) return;
    for (std::uint64_t k = 0; k < job.total; ++k) job.covered += job.covered_front[k] + job.covered_back[k];
    // fill_covered_points clears its masks.
    if (job.fg) job.mask_front = job.covered_front, job.mask_back = job.covered_back;
    bake_fill(job, job.front, job.back, job.covered_front, job.covered_back, job.offset, job.n, 1);
}

// fill_covered_points on every triangle's lattice of (f, b) (points from off[t], n[t] /
// divisor segments) under masks (mf, mb), which it clears.
void Gallery::bake_fill(BakeJob& job, std::vector<Vec3f>& f, std::vector<Vec3f>& b, std::vector<std::uint8_t>& mf,
                        std::vector<std::uint8_t>& mb, const std::vector<std::uint64_t>& off,
                        const std::vector<std::uint32_t>& n, std::uint32_t divisor) {
    parallel_for(job.tris, 1, [&](std::size_t tb, std::size_t te) {
        for (std::size_t t = tb; t < te; ++t) {
            fill_covered_points(f.data() + off[t], mf.data() + off[t], n[t] / divisor);
            fill_covered_points(b.data() + off[t], mb.data() + off[t], n[t] / divisor);
        }
    }, job.threads);
}

// The final gather over the first pass (front, back), into the direct light's arrays, which
// become the bake; sparse: onto the gathers' sub-lattice (reused), filled where covered,
// interpolated. hot_spots: the first pass's bright points leave the lattice the rays look up
// and light every gather point as lights of their own.
void Gallery::bake_final_gather_pass(BakeJob& job) {
    const BakeSettings& s = job.s;
    const std::uint32_t stride = job.stride;
    std::vector<std::uint8_t> sub_mask_front, sub_mask_back;
    if (job.sparse) {
        std::fill(job.gather_front.begin(), job.gather_front.end(), Vec3f(0, 0, 0));
        std::fill(job.gather_back.begin(), job.gather_back.end(), Vec3f(0, 0, 0));
        sub_mask_front.assign(job.sub_offset[job.tris], 0), sub_mask_back.assign(job.sub_offset[job.tris], 0);
        if (s.fill_covered)
            for (std::size_t t = 0; t < job.tris; ++t)
                for (std::uint32_t i = 0; i <= job.n[t]; i += stride)
                    for (std::uint32_t j = 0; i + j <= job.n[t]; j += stride) {
                        const std::uint64_t k = job.offset[t] + lattice_index(i, j, job.n[t]);
                        const std::uint64_t q =
                            job.sub_offset[t] + lattice_index(i / stride, j / stride, job.n[t] / stride);
                        sub_mask_front[q] = job.mask_front[k], sub_mask_back[q] = job.mask_back[k];
                    }
    }
    const HotLattice hot = extract_hot_points(scene_, job.front, job.back, job.offset, job.n, tri_v0_, tri_e1_,
                                              tri_e2_, s.hot_spots, 4096);
    stats_.bake_hot_points = hot.position.size();
    bake_final_gather_rows(job, hot);
    if (job.sparse) {
        if (s.fill_covered)
            bake_fill(job, job.gather_front, job.gather_back, sub_mask_front, sub_mask_back, job.sub_offset, job.n,
                      stride);
        bake_interpolate(job, job.gather_front, job.gather_back, job.direct_front, job.direct_back, true);
    }
    job.front = std::move(job.direct_front), job.back = std::move(job.direct_back);
    if (s.fill_covered) bake_fill(job, job.front, job.back, job.mask_front, job.mask_back, job.offset, job.n, 1);
}

// The final gather's rays and the hot points' lights at every uncovered point side (sparse:
// every sub-lattice point), row by row.
void Gallery::bake_final_gather_rows(BakeJob& job, const HotLattice& hot) {
    const BakeSettings& s = job.s;
    const std::uint32_t stride = job.stride;
    const bool sparse = job.sparse;
    parallel_for(job.rows.size(), 4, [&](std::size_t rb, std::size_t re) {
        for (std::size_t r = rb; r < re; ++r) {
            const auto [t, i] = job.rows[r];
            const std::uint32_t nt = job.n[t];
            if (!(max_component(scene_.albedo(t)) > 0)) continue;
            if (sparse && i % stride != 0) continue;
            const Vec3f N = scene_.normal(t);
            for (std::uint32_t j = 0; i + j <= nt; j += sparse ? stride : 1) {
                const std::uint64_t k = job.offset[t] + lattice_index(i, j, nt);
                const Vec3f p = bake_point(job, t, i, j);
                for (int side = 0; side < 2; ++side) {
                    if (!(job.reachable[t] >> side & 1)) continue;
                    if (s.fill_covered && (side == 0 ? job.mask_front : job.mask_back)[k]) continue;
                    const Vec3f E =
                        final_gather(p, side == 0 ? N : -N, s.final_gather, job.front, job.back, job.n, job.offset) +
                        hot_irradiance(scene_, hot, p, side == 0 ? N : -N, s.hot_samples,
                                       std::fmod(double(2 * k + side) * 0.6180339887498949, 1.0));
                    if (sparse)
                        (side == 0 ? job.gather_front : job.gather_back)[job.sub_offset[t] + lattice_index(
                            i / stride, j / stride, nt / stride)] = E;
                    else
                        (side == 0 ? job.direct_front : job.direct_back)[k] += E;
                }
            }
        }
    }, job.threads);
}

// The bake becomes the gallery's (baked() from here) and its stats are recorded (but
// bake_seconds, which bake() sets last).
void Gallery::bake_commit(BakeJob& job) {
    stats_.bake_points_covered = job.covered;
    if (!job.fg) stats_.bake_hot_points = 0;
    bake_n_ = std::move(job.n);
    job.offset.pop_back();
    bake_offset_ = std::move(job.offset);
    bake_front_ = std::move(job.front), bake_back_ = std::move(job.back);
    stats_.bake_points = job.total;
    stats_.bake_sides_skipped = job.skipped;
    stats_.spacing = job.spacing;
}

}  // namespace gigascroll

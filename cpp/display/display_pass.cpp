#include "display/display_pass.h"

#include <cmath>
#include <initializer_list>
#include <limits>

#include "common/error.h"
#include "common/parallel.h"
#include "display/eye_pass.h"
#include "display/stereo_reuse.h"

namespace gigascroll {

using namespace display;

namespace {
// The stages interleave in each thread: a pass's wall time is split among the eyes' stages in
// the proportion of the timed rows' thread time in each.
void split_wall(double wall, std::initializer_list<EyeStats*> eyes) {
    double sum = 0;
    for (const EyeStats* st : eyes) sum += st->total_seconds();
    const double f = sum > 0 ? wall / sum : 0.0;
    for (EyeStats* st : eyes)
        st->rays_seconds *= f, st->vt_seconds *= f, st->shade_seconds *= f, st->reuse_seconds *= f;
}

}  // namespace

void DisplayPass::render(const PaintingSceneView& scene, const DisplayLighting& lighting,
                         const VirtualTexture& vt, const Camera& world_eye, const DisplayOptions& o,
                         float* rgb) {
    const std::scoped_lock lock(mutex_);
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(rgb != nullptr, "display: no output image");
    check_camera(world_eye);
    const Camera eye = world_eye.moved(-scene.origin);  // into the BVH's coordinates
    origin_ = scene.origin;
    GBuffer& g = g_[0];
    g.resize(eye.width, eye.height, false);
    EyeStats& st = stats_[0] = EyeStats{};
    st.pixels = std::uint64_t(eye.width) * eye.height;
    reusing_ = false;
    hits_kept_ = o.keep_hit_points;
    frame_ = next_serial();
    split_wall(render_eye(scene, lighting, vt, eye, o, g, nullptr, nullptr, rgb, st), {&st});
    sources_.clear();
}

void DisplayPass::render_stereo(const PaintingSceneView& scene, const DisplayLighting& lighting,
                                const VirtualTexture& vt, const Camera& world_left,
                                const Camera& world_right, bool use_reuse, const DisplayOptions& o,
                                float* left_rgb, float* right_rgb) {
    const std::scoped_lock lock(mutex_);
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(left_rgb != nullptr && right_rgb != nullptr, "display: no output image");
    check_camera(world_left);
    check_camera(world_right);
    // Into the BVH's coordinates (both eyes by the same offset: the reuse is unchanged).
    const Camera left = world_left.moved(-scene.origin), right = world_right.moved(-scene.origin);
    origin_ = scene.origin;
    require(left.width == right.width && left.height == right.height,
            "display: both eyes need the same resolution");
    require(std::isfinite(o.edge_depth_ratio) && o.edge_depth_ratio >= 0,
            "display: edge_depth_ratio must be finite and >= 0");
    require(std::isfinite(o.reuse_lod_tolerance) && o.reuse_lod_tolerance >= 0,
            "display: reuse_lod_tolerance must be finite and >= 0");
    reusing_ = false;
    hits_kept_ = true;
    frame_ = next_serial();
    const std::size_t n = std::size_t(right.width) * right.height;
    if (use_reuse) {
        // The last frame's right eye left every claim unclaimed again (no 8-byte fill of the
        // image per frame); after a resize or an interrupted frame they are filled here.
        if (!claims_clear_ || claims_.size() != n) claims_.assign(n, kUnclaimed);
        claims_clear_ = false;
        sources_.resize(n);  // written by the right eye's rows (the edge release)
    }
    GBuffer& gl = g_[0];
    gl.resize(left.width, left.height, use_reuse);
    EyeStats& sl = stats_[0] = EyeStats{};
    sl.pixels = std::uint64_t(left.width) * left.height;
    GBuffer& gr = g_[1];
    gr.resize(right.width, right.height, false);
    EyeStats& sr = stats_[1] = EyeStats{};
    sr.pixels = std::uint64_t(right.width) * right.height;
    if (!use_reuse) {
        sources_.clear();
        split_wall(render_eye(scene, lighting, vt, left, o, gl, nullptr, nullptr, left_rgb, sl), {&sl});
        split_wall(render_eye(scene, lighting, vt, right, o, gr, nullptr, nullptr, right_rgb, sr), {&sr});
        return;
    }
    // The right eye with reuse. Where a point projects into the same row of both eyes, the
    // right eye's rows need only the left rows beside them: both eyes' chunks run in one
    // wavefront (parallel_wavefront), the right eye's render_eye set up inside the left one's so
    // that both passes' rows are ready together. Otherwise the whole left eye first.
    const bool interleave = o.interleave_eyes && rows_align(left, right);
    auto right_eye_pass = [&](const RunRows* run) {
        reusing_ = true;
        try {
            const double w = render_eye(scene, lighting, vt, right, o, gr, nullptr, left_rgb, right_rgb, sr, run);
            if (!run) split_wall(w, {&sr});
        } catch (...) {
            reusing_ = false;
            throw;
        }
        reusing_ = false;
    };
    const RunRows run_left = [&](std::size_t chunk_rows, const RowsBody& left_rows) {
        const RunRows run_right = [&](std::size_t right_chunk_rows, const RowsBody& right_rows) {
            GS_CHECK(right_chunk_rows == chunk_rows);
            // The right eye's chunk reads the left eye's claims on its rows and the rows
            // beside them (a left pixel claims within a row of its own), and the left rows
            // there; run right after the left chunks beside it, they are still in cache (after
            // a whole left eye, 1800 x 1920's 27 MB of claims and 41 MB of left image came
            // back from memory).
            const std::size_t n = left.height;
            parallel_wavefront((n + chunk_rows - 1) / chunk_rows,
                               [&](std::size_t c) { left_rows(c * chunk_rows, std::min(n, (c + 1) * chunk_rows)); },
                               [&](std::size_t c) { right_rows(c * chunk_rows, std::min(n, (c + 1) * chunk_rows)); },
                               o.threads);
        };
        right_eye_pass(&run_right);
    };
    const double wall = render_eye(scene, lighting, vt, left, o, gl, &right, nullptr, left_rgb, sl,
                                   interleave ? &run_left : nullptr);
    if (interleave) {
        split_wall(wall, {&sl, &sr});  // one wall time for both eyes' interleaved rows
    } else {
        split_wall(wall, {&sl});
        right_eye_pass(nullptr);
    }
    // The left eye's claims on right pixels are the right eye's reuse work.
    sr.reuse_seconds += sl.reuse_seconds;
    sl.reuse_seconds = 0;
}

EyeStats DisplayPass::left_stats() const {
    const std::scoped_lock lock(mutex_);
    return stats_[0];
}

EyeStats DisplayPass::right_stats() const {
    const std::scoped_lock lock(mutex_);
    return stats_[1];
}

std::vector<std::int32_t> DisplayPass::reuse_sources() const {
    const std::scoped_lock lock(mutex_);
    return sources_;
}

std::vector<float> DisplayPass::hit_points(int eye) const {
    const std::scoped_lock lock(mutex_);
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    require(hits_kept_, "display: the last render kept no hit points (keep_hit_points=False)");
    const GBuffer& g = g_[eye];
    std::vector<float> out(3 * g.geom.size(), std::numeric_limits<float>::quiet_NaN());
    // A reused right pixel's point is its left source's.
    const bool reused = eye == 1 && sources_.size() == g.geom.size();
    for (std::size_t i = 0; i < g.geom.size(); ++i) {
        if (g.geom[i] == kNoHit) continue;
        const Vec3f& local = reused && sources_[i] >= 0 ? g_[0].p[std::size_t(sources_[i])] : g.p[i];
        const Vec3f p(Vec3d(local) + origin_);  // in world coordinates
        out[3 * i] = p.x, out[3 * i + 1] = p.y, out[3 * i + 2] = p.z;
    }
    return out;
}

std::vector<float> DisplayPass::lods(int eye) const {
    const std::scoped_lock lock(mutex_);
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    return g_[eye].lod;
}

}  // namespace gigascroll

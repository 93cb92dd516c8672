// The display pass at full resolution, for one eye or both (issue 14): one primary ray per
// pixel through the scene's BVH, the painting's albedo sampled through the virtual texture at
// the pixel's level of detail (trilinear), times the irradiance the scene supplies (baked or
// constant), plus emission; room surfaces the same with their own albedo.
//
// Stereo reuse (VR-photon-mapping §3.3, applied to display): every left-eye hit that faces the right
// eye is projected into the right image (Camera::project, eqs. 3-5) and claims that pixel with
// an atomic compare-and-swap on (depth, left pixel); the nearest claim wins. Claimed pixels
// on a depth edge of the claimed buffer are released again (a far sample must not show through
// a near surface that no left sample happened to land on), and the right eye traces only the
// pixels left unclaimed. A claimed pixel keeps the left hit's point and its light (irradiance,
// albedo, emission: view-independent on Lambertian surfaces) and takes its texture sample at
// the right eye's level of detail for the pixel (along its centre ray, as a traced pixel's
// level) at the left point (the left eye's sample when the levels agree to within
// reuse_lod_tolerance), so the reused pixel is what the right eye computes for that point.
//
// One sweep per eye (issue 14 §5): per row, 16-ray packets are traced. With a baked lattice
// on a CPU with AVX-512, a packet wholly on one surface (nearly every packet) is deferred and
// eight at a time are, stage by stage: lit from the lattice in 16 lanes (one or two affine
// functions of a lattice cell where the packet allows, else gathered), shaded at once on a
// room surface; on a painting mapped to the packet's first pixel's uv in double and its lanes'
// offsets in float (a per-eye plane map of each painting), sampled trilinearly in 16 lanes
// from that origin (TrilinearLanes, under one VT read lock for the frame) and shaded. Other
// packets are lit through DisplayLighting::light_batch (with Embree's barycentrics) or the
// lattice's lanes, their painting pixels mapped in double and sampled in runs of one painting
// at the row's end. Per pixel the pass keeps only the hit (point, normal, ids), the level, and
// for a left eye that the right eye reuses, its light. With reuse, when the eyes' rows align
// (the headset's case), both eyes run in one wavefront of 16-row chunks: a right chunk starts
// once the left chunks beside it have made their claims, while those claims and left rows are
// still in cache.
//
// The pass keeps its buffers between frames (one DisplayPass per stream of frames). Calls on
// one pass from several threads run one at a time (a render waits for the one under way),
// and its accessors wait for a render under way: its buffers are the frame's.
#pragma once
#pragma once
#include <embree3/rtcore.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "cache/virtual_texture.h"
#include "common/vec3.h"
#include "display/display_options.h"
#include "display/gbuffer.h"
#include "display/lighting.h"
#include "display/output_image.h"
#include "display/primary_rays.h"
#include "views/camera.h"
#include "views/exhibition.h"

namespace gigascroll {

class DisplayPass {
public:
    // One eye into rgb (height x width x 3 linear floats; 0 where no surface is hit).
    void render(const PaintingSceneView& scene, const DisplayLighting& lighting,
                const VirtualTexture& vt, const Camera& eye, const DisplayOptions& options,
                float* rgb);
    // Both eyes (same resolution); reuse = false traces the right eye in full (the baseline).
    void render_stereo(const PaintingSceneView& scene, const DisplayLighting& lighting,
                       const VirtualTexture& vt, const Camera& left, const Camera& right,
                       bool reuse, const DisplayOptions& options, float* left_rgb, float* right_rgb);

    // Copies of the last frame's (taken under the pass's lock).
    EyeStats left_stats() const;
    EyeStats right_stats() const;
    // After render_stereo with reuse: per right pixel, the left pixel whose hit it reuses
    // (-1: traced), and the hit points of either eye (x, y, z per pixel; NaN where no hit;
    // InvalidArgument after a render() with keep_hit_points false).
    std::vector<std::int32_t> reuse_sources() const;
    std::vector<float> hit_points(int eye) const;
    // Per pixel of either eye: the level of detail sampled (NaN off paintings).
    std::vector<float> lods(int eye) const;

private:
    using GBuffer = display::GBuffer;
    // One eye's pass (display/eye_pass.cpp, in named steps: trace, defer, light, map, sample,
    // shade, reuse): per row, 16-ray packets traced, their hits lit and mapped to painting
    // coordinates while they are in cache, then the row's painting pixels sampled and shaded.
    // With claim_into (the left eye of a stereo pair with reuse), each packet's hits claim the
    // right eye's pixels they project to, and the painting pixels keep their light. While
    // reusing_ (the right eye), each row's claims are released on depth edges just before the
    // row is rendered; claimed pixels are not traced: they take the left hit and light, and
    // their texel at this eye's level.
    // How render_eye runs its rows: body(rb, re) on chunks of chunk_rows rows. Without one, a
    // parallel_for over the eye's rows; render_stereo's pair with reuse runs both eyes' chunks
    // in one wavefront (see render_stereo).
    using RowsBody = std::function<void(std::size_t, std::size_t)>;
    using RunRows = std::function<void(std::size_t chunk_rows, const RowsBody& body)>;
    // st's stage seconds are left as thread time of the timed rows in stage_ticks
    // (common/timing.h); the wall time of the call is returned for the caller to split among
    // the stages (split_wall).
    double render_eye(const PaintingSceneView& scene, const DisplayLighting& lighting,
                      const VirtualTexture& vt, const Camera& eye, const DisplayOptions& o,
                      GBuffer& g, const Camera* claim_into, const float* left_rgb, float* rgb,
                      EyeStats& st, const RunRows* run = nullptr);

    // Held by render, render_stereo and the accessors: one frame at a time per pass.
    mutable std::mutex mutex_;
    GBuffer g_[2];
    EyeStats stats_[2];
    std::vector<std::uint64_t> claims_;
    bool claims_clear_ = false;  // every claim is kUnclaimed (left so by the last right eye)
    bool reusing_ = false;  // the right eye being rendered reuses the left eye's hits
    bool hits_kept_ = true;  // the last frame kept the hit points (geom, p) of both eyes
    std::uint64_t frame_ = 0;  // this frame's number among all passes' (the workers' scratch)
    Vec3d origin_{0, 0, 0};    // the last frame's PaintingSceneView::origin (hit_points are world)
    std::vector<std::int32_t> sources_;
};

}  // namespace gigascroll

// What a caller chooses of the display pass (DisplayOptions) and what it reports per eye
// (EyeStats).
#pragma once
#include <cstdint>

namespace gigascroll {

struct DisplayOptions {
    // Painting texels are sRGB-encoded; true decodes the filtered value to a linear albedo.
    bool srgb_albedo = true;
    // A painting's albedo = this x its (decoded) texel (the Gallery's kPaintingReflectance).
    float painting_reflectance = 1.0f;
    // A claimed right pixel whose depth exceeds an 8-neighbour's claimed depth by more than
    // this fraction is traced instead (see the header comment).
    float edge_depth_ratio = 0.05f;
    // A reused right pixel keeps the left eye's texture sample when its level of detail
    // differs from the left eye's by at most this (0: always re-sample at the right eye's).
    float reuse_lod_tolerance = 1.0f / 1024.0f;
    // Added to every pixel's level of detail (negative: sharper).
    float lod_bias = 0.0f;
    // false: render() (one eye) does not keep the hit points for hit_points(0), 16 bytes
    // per pixel stored that nobody reads in a frame (render_stereo keeps them: the right
    // eye reuses them).
    bool keep_hit_points = true;
    // render_stereo with reuse, eyes whose rows align: both eyes' rows in one wavefront, each
    // right chunk once the left rows it reads are done (false: the whole left eye first; the
    // same frame, for tests and benchmarks).
    bool interleave_eyes = true;
    unsigned threads = 0;  // 0 = all cores
};

// Per-eye times and counts of the last render(). The stages interleave row by row, so
// rays, vt and shade are the pass's wall time split in the proportion the threads spent in
// each on every 8th row (their sum is the pass's wall time).
struct EyeStats {
    double rays_seconds = 0;     // primary rays (the right eye: only the unclaimed pixels)
    double reuse_seconds = 0;    // right eye: projection, claims and edge release
    double vt_seconds = 0;       // uv, level of detail and virtual-texture sampling
    double shade_seconds = 0;    // lighting and the final colour
    std::uint64_t pixels = 0, hits = 0, traced = 0, reused = 0, painting_pixels = 0;
    double total_seconds() const { return rays_seconds + reuse_seconds + vt_seconds + shade_seconds; }
};

}  // namespace gigascroll

// Stochastic progressive photon mapping (Hachisuka & Jensen 2009, as pbrt-v4's SPPM
// integrator implements it): a consistent estimator, whose bias and variance both go to zero
// as passes grow, where the one-shot photon map stops at its radius's bias.
//
// Each pass traces a new camera sample per pixel to its first diffuse hit (the visible
// point), adds that point's emitted and direct light, traces a new, independent photon set
// and gathers it at the visible point within the pixel's radius R. Per pixel, with M photons
// found and their reflected flux Phi (f_r included, as in pbrt), the alpha rule
//     N' = N + alpha M,   R' = R sqrt(N' / (N + M)),   tau' = (tau + Phi) (R' / R)^2
// shrinks the radius so that the density estimate keeps a fixed share alpha of new photons.
// After k passes: L = sum(direct) / k + tau / (k pi R^2) (photon powers are per pass).
//
// The hash grid is rebuilt per pass over that pass's photons (not over the visible points,
// which pbrt grids): each pixel then reads the photons around its own visible point and
// writes only its own statistics, so passes need no atomics and the image is bit-identical
// for any thread count; the cell edge is the largest current radius, so it shrinks with them.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "photon/renderer.h"

namespace gigascroll {

struct ProgressiveSettings {
    int passes = 16;                // at most this many passes
    double time_budget = 0;         // seconds; > 0 stops after the pass that exceeds it
    float alpha = 2.0f / 3.0f;      // share of new photons kept per pass (pbrt-v4's default)
    // Final gather: the visible point is where one cosine-sampled diffuse bounce from the first
    // hit lands (with that point's direct light), so the photon map's error reaches the image
    // averaged over the bounce's directions instead of as blotches of radius R.
    bool final_gather = false;
    // Passes that clip the surface disc coarsely (SurfaceDisc::Detail::Coarse, a third of the
    // rays): each pass weighs 1 / passes in the image, so the early passes' larger edge bias
    // fades while their cost, at the largest radii where nearly every gather is clipped, drops.
    int coarse_passes = 64;
    void validate() const;
};

struct ProgressiveStats {
    RenderStats render;            // sums over the passes
    int passes = 0;                // passes done
    double mean_radius = 0;        // mean final radius over pixels with a visible point
};

// Called after each pass with the pass count so far and the image at that point; lets one
// render give the whole error-versus-passes curve.
using PassCallback = std::function<void(int passes, const std::vector<float>& image, double seconds)>;

// settings.photons is the photon count per pass, settings.gather.radius the initial radius;
// settings.spp must be 1 (each pass is one camera sample per pixel). Box kernel, radius gather,
// over the sphere or (settings.gather.disc) the surface disc.
std::vector<float> render_progressive(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                      const ProgressiveSettings& progressive, ProgressiveStats& stats,
                                      const PassCallback& on_pass = {});

}  // namespace gigascroll

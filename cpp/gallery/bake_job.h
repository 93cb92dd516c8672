#pragma once
// One Gallery::bake in progress: its settings, the lattice layout (segments, offsets, work
// rows, reachable sides, edge insets) and the per-side arrays its steps pass along. The
// bake's steps (gallery.cpp: layout, first pass, gather interpolation, indirect filter,
// covered fill, final gather, commit) each read and write one of these, as the stages of a
// wavefront integrator share their queues.

#include <cstdint>
#include <utility>
#include <vector>

#include "common/vec3.h"
#include "gallery/gallery.h"

namespace gigascroll {

struct BakeJob {
    BakeJob(const BakeSettings& settings, unsigned default_threads)
        : s(settings), stride(std::uint32_t(settings.gather_stride)),
          threads(settings.threads ? settings.threads : default_threads) {}

    const BakeSettings& s;
    const std::uint32_t stride;  // gather_stride
    const unsigned threads;      // for parallel_for
    double spacing = 0;          // metres (resolved from s.spacing)
    std::size_t tris = 0;
    std::uint64_t total = 0;     // lattice points over all triangles

    // Lattice layout: triangle t has n[t] segments per edge, its points from offset[t]
    // (offset[tris] = total), its gathers' sub-lattice points from sub_offset[t].
    std::vector<std::uint32_t> n;
    std::vector<std::uint64_t> offset, sub_offset;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> rows;  // work items (triangle, row i)
    std::vector<std::uint8_t> reachable;  // per triangle, bit 0 / 1: front / back can be lit
    std::vector<float> inset;             // per triangle: BakeSettings::inset_edges' distance
    std::uint64_t skipped = 0;            // sides skip_unlit set to zero
    std::uint64_t covered = 0;            // point sides fill_covered filled

    bool filter = false;    // indirect_filter on (and a photon map to filter)
    bool fg = false;        // final_gather on (and a photon map for its first pass)
    bool separate = false;  // the gathers kept apart from the direct light until the end
    bool sparse = false;    // the final gather on the sub-lattice only

    // Per point: the irradiance (the first pass, then the bake's), the gathers on the
    // sub-lattice, the covered flags (fill_covered), the gathers apart (separate), the direct
    // light and the covered masks kept for the final gather.
    std::vector<Vec3f> front, back;
    std::vector<Vec3f> gather_front, gather_back;
    std::vector<std::uint8_t> covered_front, covered_back;
    std::vector<Vec3f> indirect_front, indirect_back;
    std::vector<Vec3f> direct_front, direct_back;
    std::vector<std::uint8_t> mask_front, mask_back;
};

}  // namespace gigascroll

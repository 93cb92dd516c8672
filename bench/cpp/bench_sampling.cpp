// Microbenchmarks of the display pass's packet sampler (TrilinearLanes::sample16 on a PacketUv):
// rows of 1800 pixels swept over a resident 16384 x 2400 painting like the display sweeps a
// painting (image rows a row of pixels apart, texels read once: first touch), and the same
// 16 rows of 112 packets sampled again and again (their texels in cache), at 0.9 texels a pixel (one
// level: a magnified view) and 1.85 (two levels blended).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "cache/virtual_texture.h"
#include "sampling/sampler.h"

using namespace gigascroll;

namespace {

constexpr std::uint32_t kWidth = 16384, kHeight = 2400;

// The painting's every tile in a 64 x 64-slot cache (as the walk benchmark's, 200 MB).
const VirtualTexture& resident_painting() {
    static const std::unique_ptr<VirtualTexture> vt = [] {
        const PackGeometry layout = PackGeometry::make(128, 4, {{kWidth, kHeight}});
        auto source = [](const TileKey& k, std::uint8_t* out) {
            for (int i = 0; i < 128 * 128 * 3; ++i) out[i] = std::uint8_t(i * 7 + k.tx * 13 + k.ty * 3 + k.level);
        };
        auto v = std::make_unique<VirtualTexture>(layout, 64, 64, source);
        std::vector<std::uint8_t> tile(v->slot_bytes());
        const std::uint32_t P = layout.payload();
        for (std::uint32_t l = 0; l < layout.paintings[0].levels(); ++l) {
            const std::uint32_t tw = (((kWidth + (1u << l) - 1) >> l) + P - 1) / P;
            const std::uint32_t th = (((kHeight + (1u << l) - 1) >> l) + P - 1) / P;
            for (std::uint32_t ty = 0; ty < th; ++ty)
                for (std::uint32_t tx = 0; tx < tw; ++tx) {
                    const TileKey k{0, l, tx, ty};
                    source(k, tile.data());
                    v->insert(k, tile.data());
                }
        }
        return v;
    }();
    return *vt;
}

// A packet of 16 pixels along an image row at t texels a pixel (its origin set per packet).
PacketUv row_packet(double t) {
    PacketUv p;
    const float lod = float(std::log2(t));
    for (int k = 0; k < 16; ++k) p.du[k] = float(k * t / kWidth), p.dv[k] = 0.0f, p.lod[k] = lod;
    return p;
}

// range(0): texels a pixel x 100; range(1): 1 to sweep the painting, 0 to repeat 16 rows.
void BM_TrilinearLanesPacket(benchmark::State& state) {
    const VirtualTexture& vt = resident_painting();
    TrilinearLanes lanes(vt, 0);
    if (!lanes.enabled()) {
        state.SkipWithError("built without AVX-512: sample16 always declines");
        return;
    }
    const double t = double(state.range(0)) / 100.0;
    const bool sweep = state.range(1) != 0;
    const int rows = int(2200 / t), width = 1800;
    const auto lock = vt.read_lock();
    alignas(64) float rgb[48];
    std::int64_t packets = 0, accepted = 0;
    int x0 = 0, y = 0, column = 0;
    PacketUv p = row_packet(t);
    for (auto _ : state) {
        // Pixels x0..x0+15 of image row y, from texel (100, 100).
        p.u0 = (100 + (x0 + column) * t) / kWidth, p.v0 = (100 + y * t) / kHeight;
        accepted += lanes.sample16(p, rgb, rgb + 16, rgb + 32);
        benchmark::DoNotOptimize(rgb);
        ++packets;
        if ((x0 += 16) + 16 > width) {  // the next image row (or, repeating, the first again)
            x0 = 0;
            y = sweep ? y + 1 : (y + 1) % 16;
            if (y == rows) y = 0, column = (column + width) % (3 * width);  // the next stretch of columns
        }
    }
    state.counters["accepted"] = double(accepted) / double(packets);
    state.SetItemsProcessed(packets);
}
BENCHMARK(BM_TrilinearLanesPacket)
    ->ArgsProduct({{90, 185}, {1, 0}})
    ->ArgNames({"texels_x100", "sweep"});

}  // namespace

BENCHMARK_MAIN();

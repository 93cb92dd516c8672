// Request processing cost of the four methods (VT-mobile-VR Fig. 11 / Table 5 "request
// computation"): the same feedback buffers (the scroll seen from 40 cm by both eyes at 1/8
// resolution plus the 512 x 512 magnifier) processed while the exhibition holds 8..40
// paintings (Table 4 sizes, 5 copies) or one painting of 4096..20480 tiles. The flag array
// scans one flag per tile of every painting, so its cost follows the tile total; the hash
// table's does not.
#include <benchmark/benchmark.h>

#include <limits>
#include <memory>
#include <set>
#include <vector>

#include "sampling/display.h"
#include "views/exhibition.h"
#include "views/feedback.h"
#include "views/request_hash.h"
#include "views/request_processing.h"
#include "views/residency.h"
#include "cache/virtual_texture.h"

using namespace gigascroll;

namespace {

const std::pair<std::uint32_t, std::uint32_t> kTable4[] = {
    {152089, 6083}, {196301, 5197}, {159010, 4339}, {102680, 5229},
    {109321, 7183}, {117968, 4722}, {91403, 11161}, {119177, 3858}};

std::vector<PaintingGeometry> exhibition(int paintings) {
    std::vector<PaintingGeometry> out;
    for (int i = 0; i < paintings; ++i) out.emplace_back(kTable4[i % 8].first, kTable4[i % 8].second);
    return out;
}

// A painting 6083 texels high whose pyramid has about `tiles` tiles in all.
PaintingGeometry painting_with_tiles(std::uint64_t tiles) {
    std::uint32_t w = 1000;
    while (PaintingGeometry(w, 6083).total_tiles() < tiles) w += 120;
    return PaintingGeometry(w, 6083);
}

// The views of VT-mobile-VR §5.3 on the scroll's wall (texel (0, 0) at (0, 1.75, 0), facing -z):
// an eye (1800 x 1920, the views.py field of view) 40 cm away and the magnifier (2.5 cm of
// painting on 512 x 512 from 20 cm), centred on x.
const double kEyeTanHalf = 900 * (12.0 / 152089) / 0.072;
Camera eye_camera(double x) {
    return Camera({x, 1.5, -0.4}, {0, 0, 1}, {0, 1, 0}, kEyeTanHalf, kEyeTanHalf * 1920 / 1800,
                  1800, 1920);
}
Camera magnifier_camera(double x) {
    return Camera({x, 1.5, -0.2}, {0, 0, 1}, {0, 1, 0}, 0.0125 / 0.2, 0.0125 / 0.2, 512, 512);
}

// The scroll alone on its wall, for the feedback and display passes.
struct ScrollScene {
    PaintingGeometry tiles{152089, 6083};
    ExhibitionScene scene;
    ScrollScene() {
        scene.add_painting(0, tiles, {0, 1.75, 0}, {1, 0, 0}, {0, -1, 0}, 12.0, 0.5);
        scene.commit();
    }
};

// Both eyes and the magnifier looking at painting 0 (the scroll, 12 m x 0.5 m) from 40 cm.
struct Feedback {
    std::vector<std::vector<std::uint64_t>> buffers;
    std::vector<FeedbackBuffer> views;
    explicit Feedback(const PaintingGeometry& tiles) {
        ExhibitionScene scene;
        scene.add_painting(0, tiles, {0, 1.75, 0}, {1, 0, 0}, {0, -1, 0},
                           12.0 * tiles.width() / 152089, 0.5);
        scene.add_box({-2, 0, 0.005}, {20, 3, 0.2});
        scene.commit();
        const double x = std::min(6.0, 6.0 * tiles.width() / 152089);
        for (double eye : {-0.0315, 0.0315}) {
            buffers.emplace_back(225 * 240);
            render_view(scene, eye_camera(x + eye), {225, 240, 0, 0}, buffers.back().data());
        }
        buffers.emplace_back(512 * 512);
        render_view(scene, magnifier_camera(x), {512, 512, 0, 0}, buffers.back().data());
        views.assign(buffers.begin(), buffers.end());
    }
};

template <typename Run>
void run_method(benchmark::State& state, const std::vector<PaintingGeometry>& paintings, Run&& run) {
    const Feedback fb(paintings[0]);
    const ResidentSet resident(paintings);
    std::uint64_t frame = 0, requests = 0;
    for (auto _ : state) requests = run(fb.views, resident, ++frame);
    std::uint64_t tiles = 0;
    for (const auto& p : paintings) tiles += p.total_tiles();
    state.counters["tiles"] = double(tiles);
    state.counters["requests"] = double(requests);
}

void add_methods(benchmark::State& state, const std::vector<PaintingGeometry>& paintings, int method) {
    switch (method) {
    case 0: {
        BasicProcessor p;
        run_method(state, paintings, [&](auto& v, auto& r, auto) { return p.process(v, r).requests.size(); });
        break;
    }
    case 1: {
        AsyncProcessor p;  // submit + wait: the work, not the latency
        run_method(state, paintings, [&](auto& v, auto& r, auto f) {
            p.submit(v, f);
            return p.drain(r).back().sets.requests.size();
        });
        break;
    }
    case 2: {
        FlagArrayProcessor p(paintings, 2);
        run_method(state, paintings, [&](auto& v, auto& r, auto) { return p.process(v, r).requests.size(); });
        break;
    }
    default: {
        HashProcessor p(16, 2);
        run_method(state, paintings, [&](auto& v, auto& r, auto f) { return p.process(v, r, f).requests.size(); });
        break;
    }
    }
}

const char* kMethods[] = {"basic", "cpu_async", "flag_array", "hash"};

void BM_Paintings(benchmark::State& state) {
    add_methods(state, exhibition(int(state.range(1))), int(state.range(0)));
    state.SetLabel(kMethods[state.range(0)]);
}
BENCHMARK(BM_Paintings)->ArgsProduct({{0, 1, 2, 3}, {8, 16, 24, 32, 40}})->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

void BM_TileTotal(benchmark::State& state) {
    add_methods(state, {painting_with_tiles(std::uint64_t(state.range(1)) * 4096)}, int(state.range(0)));
    state.SetLabel(kMethods[state.range(0)]);
}
BENCHMARK(BM_TileTotal)->ArgsProduct({{0, 1, 2, 3}, {1, 2, 3, 4, 5}})->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

// The hash slot alone (eq. 1), per request.
void BM_HashSlot(benchmark::State& state) {
    HashProcessor p(16);
    std::uint64_t key = pack_request(3, 2, 700, 40), acc = 0;
    for (auto _ : state) benchmark::DoNotOptimize(acc += p.slot(key++, HashProcessor::frame_salt(9)));
}
BENCHMARK(BM_HashSlot);

void BM_FeedbackEye(benchmark::State& state) {
    const ScrollScene s;
    const Camera cam = eye_camera(6);
    std::vector<std::uint64_t> keys(225 * 240);
    for (auto _ : state) render_view(s.scene, cam, {225, 240, 0, unsigned(state.range(0))}, keys.data());
    state.SetItemsProcessed(state.iterations() * std::int64_t(keys.size()));
}
BENCHMARK(BM_FeedbackEye)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

// The magnifier's full-resolution feedback as the frame loop asks for it (keys, lambda and
// uv): 2.5 cm of the scroll on 512 x 512 pixels from 20 cm.
void BM_FeedbackMagnifier(benchmark::State& state) {
    const ScrollScene s;
    const Camera cam = magnifier_camera(6);
    std::vector<std::uint64_t> keys(512 * 512);
    std::vector<float> lod(keys.size());
    std::vector<double> uv(2 * keys.size());
    for (auto _ : state)
        render_view(s.scene, cam, {512, 512, 0, unsigned(state.range(0))}, keys.data(),
                        state.range(1) ? lod.data() : nullptr, state.range(1) ? uv.data() : nullptr);
    state.SetItemsProcessed(state.iterations() * std::int64_t(keys.size()));
}
BENCHMARK(BM_FeedbackMagnifier)->ArgsProduct({{1, 2}, {0, 1}})->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

// Embree alone on the magnifier's rays (one thread, 16-ray packets along each row, the same
// set-up as render_view's): the part of BM_FeedbackMagnifier/1/0 that is ray tracing.
void BM_EmbreeMagnifier(benchmark::State& state) {
    const ScrollScene s;
    const Camera cam = magnifier_camera(6);
    RTCRayHit16 packet;
    alignas(64) int valid[16];
    for (int k = 0; k < 16; ++k) {
        valid[k] = -1;
        packet.ray.org_x[k] = float(cam.position.x), packet.ray.org_y[k] = float(cam.position.y);
        packet.ray.org_z[k] = float(cam.position.z);
        packet.ray.tnear[k] = 0.f, packet.ray.time[k] = 0.f, packet.ray.mask[k] = ~0u;
        packet.ray.id[k] = k, packet.ray.flags[k] = 0;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    std::int64_t hits = 0;
    for (auto _ : state) {
        for (int row = 0; row < 512; ++row) {
            const Vec3d row_dir = cam.forward + cam.screen_y(row + 0.5) * cam.up;
            for (int i0 = 0; i0 < 512; i0 += 16) {
                for (int k = 0; k < 16; ++k) {
                    const Vec3d d = row_dir + cam.screen_x(i0 + k + 0.5) * cam.right;
                    packet.ray.dir_x[k] = float(d.x), packet.ray.dir_y[k] = float(d.y);
                    packet.ray.dir_z[k] = float(d.z);
                    packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
                    packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                }
                RTCIntersectContext context;
                rtcInitIntersectContext(&context);
                context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
                rtcIntersect16(valid, s.scene.handle(), &context, &packet);
                hits += packet.hit.geomID[0] != RTC_INVALID_GEOMETRY_ID;
            }
        }
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(state.iterations() * 512 * 512);
}
BENCHMARK(BM_EmbreeMagnifier)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

// The display pass (display_view) of a view whose requested tiles are all resident, as in
// the frame loop's steady state: the magnifier at display step 2 (arg 0) or an eye at its
// feedback resolution (arg 1); arg 1 of the pair: threads.
void BM_Display(benchmark::State& state) {
    const ScrollScene s;
    const bool eye = state.range(0) == 1;
    const Camera cam = eye ? eye_camera(6) : magnifier_camera(6);
    FeedbackOptions o{eye ? 225u : 512u, eye ? 240u : 512u, 0, 0, eye ? 1u : 2u};
    const std::uint32_t w = o.width, h = o.height, dw = display_extent(w, o.display_step),
                        dh = display_extent(h, o.display_step);
    std::vector<std::uint64_t> keys(std::size_t(w) * h);
    std::vector<float> lod(std::size_t(dw) * dh);
    std::vector<double> uv(2 * lod.size());
    render_view(s.scene, cam, o, keys.data(), lod.data(), uv.data());
    VirtualTexture vt(PackGeometry::make(128, 4, {{152089, 6083}}), 30, 30,
                      [](const TileKey&, std::uint8_t* d) { std::fill_n(d, 128 * 128 * 3, 128); });
    std::vector<std::uint8_t> texels(128 * 128 * 3);
    for (std::size_t i = 0; i < texels.size(); ++i) texels[i] = std::uint8_t(i * 2654435761u >> 24);
    for (std::uint64_t k : std::set<std::uint64_t>(keys.begin(), keys.end())) {
        if (k == kNoRequest) continue;
        const TileKey r = unpack_request(k);
        vt.insert({r.painting, r.level, r.tx, r.ty}, texels.data());
    }
    std::vector<float> out(3 * lod.size());
    for (auto _ : state)
        display_view(vt, keys.data(), lod.data(), uv.data(), w, h, o.display_step, out.data(),
                     unsigned(state.range(1)));
    state.SetItemsProcessed(state.iterations() * std::int64_t(lod.size()));
}
BENCHMARK(BM_Display)->ArgsProduct({{0, 1}, {1, 2}})->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

// The full-resolution display pass and its stereo reuse, on two threads (the claims are an
// atomic compare-and-swap; `make sanitize` runs this under TSan): a uniform painting on a grey
// wall with a post in front, so every reused pixel must show exactly what a fully traced right
// eye shows there, except on the silhouettes of the post and the painting.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>

#include "cache/virtual_texture.h"
#include "pack/geometry.h"
#include "display/display_pass.h"
#include "views/camera.h"
#include "views/exhibition.h"

using namespace gigascroll;

namespace {

struct Wall {
    PackGeometry layout = PackGeometry::make(16, 2, {{240, 60}});
    VirtualTexture vt{layout, 8, 8, [](const TileKey&, std::uint8_t* out) {
                          for (std::size_t i = 0; i < 16 * 16; ++i)
                              out[3 * i] = 200, out[3 * i + 1] = 120, out[3 * i + 2] = 40;
                      }};
    ExhibitionScene scene;
    Wall() {
        scene.add_painting(0, layout.paintings[0], {0.0, 1.6, 0.0}, {1, 0, 0}, {0, -1, 0}, 0.8, 0.2);
        scene.add_box({-2, 0, 0.005}, {3, 3, 0.2});         // the wall behind
        scene.add_box({0.38, 1.0, -0.15}, {0.42, 2.0, -0.11});  // a 4 cm post in front
        scene.commit();
    }
};

Camera eye(double x, std::uint32_t w, std::uint32_t h) {
    return Camera({x, 1.5, -0.5}, {0, 0, 1}, {0, 1, 0}, 0.6, 0.6 * h / w, w, h);
}

}  // namespace

TEST(StereoDisplay, ReusedPixelsShowWhatTheRightEyeTraces) {
    Wall room;
    const std::uint32_t w = 160, h = 120;
    const Camera left = eye(0.4 - 0.0315, w, h), right = eye(0.4 + 0.0315, w, h);
    UnlitLighting lighting;
    DisplayOptions o;
    o.threads = 2;
    std::vector<float> l(3 * w * h), r(3 * w * h), l0(3 * w * h), r0(3 * w * h);
    DisplayPass reuse, full;
    reuse.render_stereo(room.scene.view(), lighting, room.vt, left, right, true, o, l.data(), r.data());
    full.render_stereo(room.scene.view(), lighting, room.vt, left, right, false, o, l0.data(), r0.data());
    const EyeStats st = reuse.right_stats();
    const std::vector<std::int32_t> sources = reuse.reuse_sources();
    EXPECT_EQ(st.traced + st.reused, st.pixels);
    EXPECT_GT(st.reused, st.pixels / 2);
    EXPECT_EQ(full.right_stats().traced, st.pixels);
    EXPECT_EQ(l, l0);  // the left eye does not depend on reuse
    std::size_t reused = 0, differ = 0;
    for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
        if (sources[i] < 0) continue;
        ++reused;
        bool same = true;
        for (int c = 0; c < 3; ++c) same &= std::abs(r[3 * i + c] - r0[3 * i + c]) < 1e-6f;
        differ += !same;
    }
    EXPECT_EQ(reused, st.reused);
    // Only silhouette pixels (a reused point half a pixel from the traced pixel centre, on
    // the other side of an edge) may differ: the post's two edges and the painting's outline.
    EXPECT_LT(differ, std::size_t(2 * h + 2 * w)) << differ << " of " << reused;
    // The post occludes part of the painting for the right eye but not for the left: no reused
    // pixel may show the painting where the traced right eye sees the post (dark grey).
    for (std::size_t i = 0; i < std::size_t(w) * h; ++i) {
        if (sources[i] < 0) continue;
        const bool traced_post = std::abs(r0[3 * i] - 0.5f) < 1e-6f && std::abs(r0[3 * i + 2] - 0.5f) < 1e-6f;
        const bool reused_painting = r[3 * i] > 0.5f && r[3 * i + 2] < 0.1f;
        const std::size_t x = i % w;
        const bool edge = x > 0 && x + 1 < w &&
                          (std::abs(r0[3 * (i - 1)] - r0[3 * i]) > 1e-6f || std::abs(r0[3 * (i + 1)] - r0[3 * i]) > 1e-6f);
        if (!edge) EXPECT_FALSE(traced_post && reused_painting) << "pixel " << i;
    }
}

// The eyes' chunks in one wavefront (the default) give the frame of the whole left eye first:
// a right chunk started before the left rows beside it had claimed its pixels would release
// other claims. On one thread the wavefront's order alone must hold; on two, its waits.
TEST(StereoDisplay, TheEyesInterleavedGiveTheFrameOfTheLeftEyeFirst) {
    Wall room;
    const std::uint32_t w = 160, h = 200;  // 13 chunks of 16 rows
    const Camera left = eye(0.4 - 0.0315, w, h), right = eye(0.4 + 0.0315, w, h);
    UnlitLighting lighting;
    for (unsigned threads : {1u, 2u}) {
        DisplayOptions o;
        o.threads = threads;
        std::vector<float> l(3 * w * h), r(3 * w * h), l0(3 * w * h), r0(3 * w * h);
        DisplayPass interleaved, sequential;
        for (int frame = 0; frame < 2; ++frame) {  // the second reuses the cleared claims
            interleaved.render_stereo(room.scene.view(), lighting, room.vt, left, right, true, o,
                                      l.data(), r.data());
            o.interleave_eyes = false;
            sequential.render_stereo(room.scene.view(), lighting, room.vt, left, right, true, o,
                                     l0.data(), r0.data());
            o.interleave_eyes = true;
            EXPECT_EQ(l, l0);
            EXPECT_EQ(r, r0);
            EXPECT_EQ(interleaved.reuse_sources(), sequential.reuse_sources());
            EXPECT_EQ(interleaved.right_stats().reused, sequential.right_stats().reused);
            EXPECT_EQ(interleaved.right_stats().traced, sequential.right_stats().traced);
            EXPECT_GT(interleaved.right_stats().reused, interleaved.right_stats().pixels / 2);
        }
    }
}

TEST(StereoDisplay, BareRaysSeeWhatTheDisplaySees) {
    Wall room;
    const Camera c = eye(0.4, 64, 48);
    std::uint64_t hits = 0;
    EXPECT_GE(cast_primary_rays(room.scene.handle(), c, 2, &hits), 0.0);
    EXPECT_EQ(hits, 64u * 48u);  // the wall fills the view
    DisplayPass d;
    std::vector<float> rgb(3 * 64 * 48);
    d.render(room.scene.view(), UnlitLighting{}, room.vt, c, DisplayOptions{}, rgb.data());
    EXPECT_EQ(d.left_stats().hits, hits);
    EXPECT_GT(d.left_stats().painting_pixels, 0u);
}

// One pass shared by threads (render, render_stereo and the accessors at two sizes): each
// call's frame equals a pass of its own (they used to resize each other's buffers; TSan
// checks the lock under `make sanitize`).
TEST(StereoDisplay, OnePassSharedByThreadsGivesTheSerialFrames) {
    Wall room;
    const std::uint32_t sizes[2][2] = {{96, 64}, {40, 32}};
    DisplayOptions o;
    o.threads = 1;
    std::vector<float> want[2][2];  // [size][eye] from a pass of its own
    for (int s = 0; s < 2; ++s) {
        const std::uint32_t w = sizes[s][0], h = sizes[s][1];
        want[s][0].resize(3 * w * h), want[s][1].resize(3 * w * h);
        DisplayPass own;
        own.render_stereo(room.scene.view(), UnlitLighting{}, room.vt, eye(0.37, w, h), eye(0.43, w, h), true, o,
                          want[s][0].data(), want[s][1].data());
    }
    DisplayPass shared;
    std::vector<int> wrong(4, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            const int s = t % 2;
            const std::uint32_t w = sizes[s][0], h = sizes[s][1];
            std::vector<float> l(3 * w * h), r(3 * w * h);
            for (int k = 0; k < 6; ++k) {
                if ((k + t) % 2) {
                    shared.render_stereo(room.scene.view(), UnlitLighting{}, room.vt, eye(0.37, w, h),
                                         eye(0.43, w, h), true, o, l.data(), r.data());
                    wrong[std::size_t(t)] += l != want[s][0] || r != want[s][1];
                } else {
                    shared.render(room.scene.view(), UnlitLighting{}, room.vt, eye(0.37, w, h), o, l.data());
                    wrong[std::size_t(t)] += l != want[s][0];
                }
                wrong[std::size_t(t)] += shared.lods(0).empty() || shared.left_stats().pixels == 0;
                (void)shared.reuse_sources();
            }
        });
    for (std::thread& th : threads) th.join();
    EXPECT_EQ(wrong, std::vector<int>(4, 0));
}

// The tile-pack builder against a brute-force reference: every tile of every level is the
// exact average of the level-0 pixels under it, borders clamped; bad calls are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "common/error.h"
#include "pack/builder.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"

using namespace gigascroll;

namespace {

// Exact average of the real level-0 pixels under texel (x, y) of level l.
double brute_texel(const std::vector<std::uint8_t>& img, std::uint32_t w, std::uint32_t h,
                   std::uint32_t l, std::int64_t x, std::int64_t y, int c) {
    double sum = 0, n = 0;
    for (std::int64_t yy = y << l; yy < std::min<std::int64_t>(h, (y + 1) << l); ++yy)
        for (std::int64_t xx = x << l; xx < std::min<std::int64_t>(w, (x + 1) << l); ++xx) {
            sum += img[(std::size_t(yy) * w + xx) * 3 + c];
            n += 1;
        }
    return sum / n;
}

void expect_matches_reference(const TilePack& pack, const std::vector<std::uint8_t>& img,
                              std::uint32_t w, std::uint32_t h) {
    const auto& g = pack.paintings().at(0).geometry;
    const std::uint32_t T = pack.tile_size(), b = pack.border(), P = pack.payload();
    std::vector<std::uint8_t> tile(pack.tile_bytes());
    for (std::uint32_t l = 0; l < g.levels(); ++l) {
        const auto& lv = g.level(l);
        for (std::uint32_t ty = 0; ty < lv.tiles_y; ++ty)
            for (std::uint32_t tx = 0; tx < lv.tiles_x; ++tx) {
                ASSERT_TRUE(pack.has_tile(0, l, tx, ty));
                pack.read_tile(0, l, tx, ty, tile.data());
                for (std::uint32_t j = 0; j < T; ++j)
                    for (std::uint32_t i = 0; i < T; ++i) {
                        const std::int64_t x = std::clamp<std::int64_t>(std::int64_t(tx) * P - b + i, 0, lv.width - 1);
                        const std::int64_t y = std::clamp<std::int64_t>(std::int64_t(ty) * P - b + j, 0, lv.height - 1);
                        for (int c = 0; c < 3; ++c)
                            ASSERT_LE(std::abs(tile[(j * T + i) * 3 + c] - brute_texel(img, w, h, l, x, y, c)), 0.5)
                                << "level " << l << " tile " << tx << "," << ty;
                    }
            }
    }
}

}  // namespace

TEST(PackBuilder, RawAndZstdMatchBruteForceOnOddSizes) {
    for (auto [w, h] : {std::pair{45u, 23u}, std::pair{1u, 1u}, std::pair{70u, 3u}}) {
        const auto img = random_image(w, h, w * 31 + h);
        for (Codec codec : {Codec::Raw, Codec::Zstd}) {
            TempDir dir;
            build(dir.path, img, w, h, 8, 2, codec, 5, 2);
            TilePack pack(dir.path.string());
            EXPECT_EQ(pack.codec(), codec);
            expect_matches_reference(pack, img, w, h);
        }
    }
}

TEST(PackBuilder, RejectsBadCalls) {
    TempDir dir;
    PackOptions o;
    o.tile_size = 8;
    o.border = 1;
    PackBuilder b(dir.path.string(), o);
    EXPECT_THROW(b.add_rows(nullptr, 1, 4), InvalidArgument);  // no painting
    b.begin_painting({"a", "", "", 4, 4, 0, 0});
    std::vector<std::uint8_t> row(5 * 3);
    EXPECT_THROW(b.add_rows(row.data(), 1, 5), InvalidArgument);       // wrong width
    EXPECT_THROW(b.add_rows(row.data(), 5, 4), InvalidArgument);       // too many rows
    EXPECT_THROW(b.end_painting(), InvalidArgument);                   // rows missing
    EXPECT_THROW(PackBuilder((dir.path / "no" / "such").string(), o), IoError);
    o.border = 4;
    EXPECT_THROW(PackBuilder(dir.path.string(), o), InvalidArgument);
}

// Tile-pack builder, reader and page layout against brute-force references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>
#include <vector>

#include "common/error.h"
#include "pack/ink_landscape.h"
#include "pack/builder.h"
#include "pack/page_layout.h"
#include "pack/reader.h"

using namespace gigascroll;
namespace fs = std::filesystem;

namespace {

struct TempDir {
    fs::path path;
    TempDir() {
        std::string tmpl = (fs::temp_directory_path() / "gigascroll-test-XXXXXX").string();
        path = ::mkdtemp(tmpl.data());
    }
    ~TempDir() { fs::remove_all(path); }
};

std::vector<std::uint8_t> random_image(std::uint32_t w, std::uint32_t h, unsigned seed) {
    std::mt19937 rng(seed);
    std::vector<std::uint8_t> img(std::size_t(w) * h * 3);
    for (auto& v : img) v = static_cast<std::uint8_t>(rng() & 255);
    return img;
}

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

void build(const fs::path& dir, const std::vector<std::uint8_t>& img, std::uint32_t w,
           std::uint32_t h, std::uint32_t tile, std::uint32_t border, Codec codec,
           std::uint32_t band, unsigned threads) {
    PackOptions o;
    o.tile_size = tile;
    o.border = border;
    o.codec = codec;
    o.threads = threads;
    PackBuilder b(dir.string(), o);
    b.begin_painting({"img", "test", "none", w, h, 0, 0});
    for (std::uint32_t y = 0; y < h; y += band)
        b.add_rows(img.data() + std::size_t(y) * w * 3, std::min(band, h - y), w);
    b.end_painting();
    const PaintingGeometry g = PaintingGeometry(w, h, tile, border);
    b.finish(g.page_table_width(), g.page_table_height());
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

TEST(PackGeometry, Table4PaintingHasPowerOfTwoPageTable) {
    const PaintingGeometry g = PaintingGeometry(152089, 6083, 128, 4);
    EXPECT_EQ(g.page_table_width(), 2048u);
    EXPECT_EQ(g.page_table_height(), 64u);
    EXPECT_EQ(g.level(0).tiles_x, 1268u);
    EXPECT_EQ(g.level(0).tiles_y, 51u);
    EXPECT_EQ(g.levels(), 12u);
    EXPECT_LE(g.level(g.levels() - 1).width, 120u);
    EXPECT_GT(g.level(g.levels() - 2).width, 120u);
    EXPECT_THROW(PaintingGeometry(10, 10, 8, 4), InvalidArgument);
    EXPECT_THROW(PaintingGeometry(0, 10, 128, 4), InvalidArgument);
}

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

TEST(TilePack, ErrorsAreClear) {
    EXPECT_THROW(TilePack("/nonexistent/pack"), IoError);
    TempDir dir;
    const auto img = random_image(30, 20, 1);
    build(dir.path, img, 30, 20, 8, 1, Codec::Raw, 20, 1);
    {
        TilePack pack(dir.path.string());
        EXPECT_THROW(pack.has_tile(1, 0, 0, 0), InvalidArgument);
        EXPECT_THROW(pack.has_tile(0, 9, 0, 0), InvalidArgument);
        EXPECT_THROW(pack.has_tile(0, 0, 8, 0), InvalidArgument);   // 8-wide page table
        EXPECT_FALSE(pack.has_tile(0, 0, 5, 0));                    // padding: 5 real tiles
        EXPECT_THROW(pack.locate(0, 0, 5, 0), InvalidArgument);
        const TileLocation loc = pack.locate(0, 0, 1, 1);
        // Corrupt one byte of that tile.
        std::fstream f(dir.path / "tiles.bin", std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(static_cast<std::streamoff>(loc.offset + 7));
        f.put('\x5a' ^ 0x7f);
        f.close();
        std::vector<std::uint8_t> out(pack.tile_bytes());
        EXPECT_THROW(pack.read_tile(0, 0, 1, 1, out.data()), IoError);
        EXPECT_NO_THROW(pack.read_tile(0, 0, 0, 0, out.data()));
    }
    fs::resize_file(dir.path / "index.bin", fs::file_size(dir.path / "index.bin") - 1);
    EXPECT_THROW(TilePack(dir.path.string()), IoError);
}

TEST(TilePack, ConcurrentReadsAgreeWithSerialReads) {
    TempDir dir;
    const std::uint32_t w = 200, h = 90;
    std::vector<std::uint8_t> img(std::size_t(w) * h * 3);
    render_ink_landscape(w, h, 0, h, 3, img.data(), 2);
    build(dir.path, img, w, h, 16, 2, Codec::Zstd, 7, 2);
    const TilePack pack(dir.path.string());
    struct Key { std::uint32_t l, tx, ty; };
    std::vector<Key> keys;
    for (std::uint32_t l = 0; l < pack.paintings()[0].geometry.levels(); ++l)
        for (std::uint32_t ty = 0; ty < pack.paintings()[0].geometry.level(l).tiles_y; ++ty)
            for (std::uint32_t tx = 0; tx < pack.paintings()[0].geometry.level(l).tiles_x; ++tx)
                keys.push_back({l, tx, ty});
    std::vector<std::vector<std::uint8_t>> serial(keys.size(), std::vector<std::uint8_t>(pack.tile_bytes()));
    for (std::size_t i = 0; i < keys.size(); ++i)
        pack.read_tile(0, keys[i].l, keys[i].tx, keys[i].ty, serial[i].data());
    std::vector<int> mismatches(4, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            std::vector<std::uint8_t> out(pack.tile_bytes());
            for (int rep = 0; rep < 5; ++rep)
                for (std::size_t i = t; i < keys.size(); i += 3) {
                    pack.read_tile(0, keys[i].l, keys[i].tx, keys[i].ty, out.data());
                    mismatches[t] += out != serial[i];
                }
        });
    for (auto& th : threads) th.join();
    for (int m : mismatches) EXPECT_EQ(m, 0);
}

TEST(PageLayout, PackersAreAlignedDisjointAtEveryLevelAndDeterministic) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 10; ++trial) {
        std::vector<TableSize> tables(1 + rng() % 12);
        for (auto& t : tables) t = {1u << (rng() % 6), 1u << (rng() % 6)};
        for (const PageLayout& layout : {shelf_layout(tables), brkga_layout(tables, {.seed = 3})}) {
            ASSERT_NO_THROW(check_layout(tables, layout));
            // Brute force over every page-table level a table still covers whole entries.
            for (std::uint32_t l = 0; (1u << l) <= std::max(layout.width, layout.height); ++l) {
                const std::uint32_t gw = std::max(1u, layout.width >> l), gh = std::max(1u, layout.height >> l);
                std::vector<int> grid(std::size_t(gw) * gh, 0);
                for (std::size_t i = 0; i < tables.size(); ++i) {
                    if ((1u << l) > std::min(tables[i].width, tables[i].height)) continue;
                    const auto [x, y] = layout.offsets[i];
                    ASSERT_EQ((x >> l) << l, x);
                    ASSERT_EQ((y >> l) << l, y);
                    for (std::uint32_t yy = y >> l; yy < (y >> l) + (tables[i].height >> l); ++yy)
                        for (std::uint32_t xx = x >> l; xx < (x >> l) + (tables[i].width >> l); ++xx)
                            ASSERT_EQ(++grid[std::size_t(yy) * gw + xx], 1);
                }
            }
        }
        const PageLayout a = brkga_layout(tables, {.seed = 11}), b = brkga_layout(tables, {.seed = 11});
        EXPECT_EQ(a.offsets, b.offsets);
        EXPECT_GE(a.fill_ratio, shelf_layout(tables).fill_ratio);
    }
    EXPECT_THROW(shelf_layout({{3, 4}}), InvalidArgument);
    EXPECT_THROW(check_layout({{4, 4}, {4, 4}}, PageLayout{8, 8, {{0, 0}, {0, 0}}, 0}), InvalidArgument);
    EXPECT_THROW(check_layout({{4, 4}}, PageLayout{8, 8, {{2, 0}}, 0}), InvalidArgument);
}

TEST(InkLandscape, BandsAreIndependent) {
    const std::uint32_t w = 300, h = 50;
    std::vector<std::uint8_t> whole(std::size_t(w) * h * 3), band(std::size_t(w) * 10 * 3);
    render_ink_landscape(w, h, 0, h, 1, whole.data(), 2);
    render_ink_landscape(w, h, 20, 10, 1, band.data(), 1);
    EXPECT_TRUE(std::equal(band.begin(), band.end(), whole.begin() + std::size_t(20) * w * 3));
    EXPECT_THROW(render_ink_landscape(w, h, 45, 10, 1, band.data()), InvalidArgument);
}

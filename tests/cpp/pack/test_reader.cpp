// The tile-pack reader: clear errors on bad keys, corrupt tiles and truncated files, and
// concurrent reads equal to serial ones.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "common/error.h"
#include "pack/ink_landscape.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"

using namespace gigascroll;
namespace fs = std::filesystem;

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
        std::fstream f(dir.path / tile_file_name(0), std::ios::in | std::ios::out | std::ios::binary);
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

// The tile loader in both modes against direct reads of the pack and the source image:
// every command answered exactly once with the right bytes, back-pressure without loss,
// per-tile errors, and shutdown with commands in flight.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <thread>
#include <unistd.h>

#include "common/error.h"
#include "pack/builder.h"
#include "loading/tile_loader.h"
#include "pack/reader.h"

using namespace gigascroll;
namespace fs = std::filesystem;

namespace {

constexpr std::uint32_t W = 300, H = 170, T = 32, E = 2;

// A small raw pack of a random image, built once per test binary run.
class LoaderTest : public ::testing::TestWithParam<std::tuple<LoaderMode, unsigned>> {
protected:
    static void SetUpTestSuite() {
        dir_ = fs::temp_directory_path() / ("gigascroll_loader_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        std::mt19937 rng(1);
        image_.resize(std::size_t(W) * H * 3);
        for (auto& b : image_) b = std::uint8_t(rng());
        PackOptions o;
        o.tile_size = T;
        o.border = E;
        o.threads = 1;
        PackBuilder b(dir_.string(), o);
        const PaintingGeometry g = PaintingGeometry(W, H, T, E);
        b.begin_painting(PaintingSpec{"test", "array", "none", W, H, 0, 0});
        b.add_rows(image_.data(), H, W);
        b.end_painting();
        b.finish(g.page_table_width(), g.page_table_height());
    }
    static void TearDownTestSuite() { fs::remove_all(dir_); }

    static std::vector<TileKey> all_keys(const TilePack& pack) {
        std::vector<TileKey> keys;
        const auto& g = pack.paintings()[0].geometry;
        for (std::uint32_t l = 0; l < g.levels(); ++l)
            for (std::uint32_t y = 0; y < g.level(l).tiles_y; ++y)
                for (std::uint32_t x = 0; x < g.level(l).tiles_x; ++x) keys.push_back({0, l, x, y});
        return keys;
    }

    // Polls until `count` results arrived (bounded: a hang fails instead of blocking ctest).
    static std::vector<LoadedTile> poll_n(TileLoader& loader, std::size_t count, bool release = true) {
        std::vector<LoadedTile> all, batch;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
        while (all.size() < count && std::chrono::steady_clock::now() < deadline) {
            batch.clear();
            if (loader.poll(batch, 64) == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
            for (auto& r : batch) {
                if (r.buffer >= 0) {
                    r.error.assign(reinterpret_cast<const char*>(loader.data(r.buffer)), loader.tile_bytes());
                    if (release) loader.release(r.buffer);
                }
                all.push_back(std::move(r));  // tile bytes kept in `error` for the checks
            }
        }
        return all;
    }

    static inline fs::path dir_;
    static inline std::vector<std::uint8_t> image_;
};

}  // namespace

TEST_P(LoaderTest, EveryCommandAnsweredOnceWithTheRightBytes) {
    const auto [mode, threads] = GetParam();
    TilePack pack(dir_.string());
    LoaderOptions o;
    o.queue_capacity = 16;  // small: exercises the backlog and back-pressure
    o.pool_tiles = 5;
    TileLoader loader(pack, mode, threads, o);
    auto keys = all_keys(pack);
    std::vector<TileKey> commands;
    for (int copy = 0; copy < 3; ++copy) commands.insert(commands.end(), keys.begin(), keys.end());
    loader.submit(commands.data(), commands.size());
    const auto results = poll_n(loader, commands.size());
    ASSERT_EQ(results.size(), commands.size());
    std::map<std::uint64_t, int> seen;
    std::vector<std::uint8_t> direct(pack.tile_bytes());
    for (const auto& r : results) {
        ASSERT_GE(r.buffer, 0);
        ++seen[r.key.packed()];
        pack.read_tile(0, r.key.level, r.key.tx, r.key.ty, direct.data());
        ASSERT_EQ(std::memcmp(r.error.data(), direct.data(), direct.size()), 0);
        if (r.key.level == 0) {  // payload texels are the source image's
            const std::uint32_t x0 = r.key.tx * (T - 2 * E), y0 = r.key.ty * (T - 2 * E);
            for (std::uint32_t y = 0; y < T - 2 * E && y0 + y < H; ++y)
                for (std::uint32_t x = 0; x < T - 2 * E && x0 + x < W; ++x)
                    for (int c = 0; c < 3; ++c)
                        ASSERT_EQ(std::uint8_t(r.error[((E + y) * T + E + x) * 3 + c]),
                                  image_[((y0 + y) * std::size_t(W) + x0 + x) * 3 + c]);
        }
    }
    EXPECT_EQ(seen.size(), keys.size());
    for (const auto& [k, n] : seen) EXPECT_EQ(n, 3);
    const LoaderStats s = loader.stats();
    EXPECT_EQ(s.loaded, commands.size());
    EXPECT_EQ(s.failed, 0u);
    EXPECT_EQ(s.backlog, 0u);
}

TEST_P(LoaderTest, CorruptTileIsAnErrorResultAndTheThreadsSurvive) {
    const auto [mode, threads] = GetParam();
    // A private copy of the pack with one tile's bytes flipped.
    const fs::path copy = dir_.string() + "_corrupt_" + std::to_string(int(mode)) + std::to_string(threads);
    fs::remove_all(copy);
    fs::copy(dir_, copy);
    TilePack pack(copy.string());
    const TileLocation loc = pack.locate(0, 0, 1, 1);
    {
        std::FILE* f = std::fopen((copy / tile_file_name(0)).c_str(), "r+b");
        ASSERT_TRUE(f);
        std::fseek(f, long(loc.offset + 10), SEEK_SET);
        const int c = std::fgetc(f);
        std::fseek(f, long(loc.offset + 10), SEEK_SET);
        std::fputc(c ^ 0x5A, f);
        std::fclose(f);
    }
    TileLoader loader(pack, mode, threads);
    std::vector<TileKey> commands = {{0, 0, 1, 1}, {0, 0, 0, 0}, {0, 0, 1, 1}, {0, 1, 0, 0}};
    loader.submit(commands.data(), commands.size());
    auto results = poll_n(loader, commands.size());
    ASSERT_EQ(results.size(), 4u);
    int errors = 0;
    for (const auto& r : results) {
        if (r.key == TileKey{0, 0, 1, 1}) {
            EXPECT_LT(r.buffer, 0);
            EXPECT_NE(r.error.find("checksum"), std::string::npos) << r.error;
            ++errors;
        } else {
            EXPECT_GE(r.buffer, 0);
        }
    }
    EXPECT_EQ(errors, 2);
    // The threads are still alive.
    loader.submit(commands.data() + 1, 1);
    EXPECT_EQ(poll_n(loader, 1).size(), 1u);
    EXPECT_EQ(loader.stats().failed, 2u);
    loader.close();

    // Error results need no buffer, so unpolled ones fill the result queue: the threads
    // then hold a finished result each when closed, which must still come out of poll().
    LoaderOptions o;
    o.queue_capacity = 8;
    o.pool_tiles = 2;
    TileLoader stuck(pack, mode, threads, o);
    std::vector<TileKey> bad(200, TileKey{0, 0, 1, 1});
    stuck.submit(bad.data(), bad.size());
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    stuck.close();
    std::vector<LoadedTile> out;
    while (stuck.poll(out, 7) > 0) {
    }
    const LoaderStats s = stuck.stats();
    EXPECT_EQ(s.failed, out.size());
    EXPECT_EQ(s.loaded, 0u);
    EXPECT_EQ(s.failed + s.cancelled, bad.size());
    fs::remove_all(copy);
}

TEST_P(LoaderTest, CloseWithCommandsInFlightLosesNoFinishedTile) {
    const auto [mode, threads] = GetParam();
    TilePack pack(dir_.string());
    LoaderOptions o;
    o.queue_capacity = 256;
    o.pool_tiles = 8;
    TileLoader loader(pack, mode, threads, o);
    auto keys = all_keys(pack);
    std::vector<TileKey> commands;
    while (commands.size() < 3000) commands.insert(commands.end(), keys.begin(), keys.end());
    loader.submit(commands.data(), commands.size());
    const std::size_t early = poll_n(loader, 20).size();
    // Results are not released: the threads run out of buffers and stop with work queued.
    std::vector<LoadedTile> held;
    loader.poll(held, 1000);
    loader.close();  // must not hang
    std::vector<LoadedTile> rest;
    while (loader.poll(rest, 1000) > 0) {
    }
    const LoaderStats s = loader.stats();
    EXPECT_EQ(early + held.size() + rest.size(), s.loaded + s.failed);
    EXPECT_EQ(s.loaded + s.failed + s.cancelled, commands.size());
    EXPECT_GT(s.cancelled, 0u);
    EXPECT_THROW(loader.submit(commands.data(), 1), InvalidArgument);
}

TEST_P(LoaderTest, RejectsKeysOutsideThePack) {
    const auto [mode, threads] = GetParam();
    TilePack pack(dir_.string());
    TileLoader loader(pack, mode, threads);
    const TileKey bad[] = {{0, 0, 0, 0}, {0, 0, 99, 0}};
    EXPECT_THROW(loader.submit(bad, 2), InvalidArgument);
    EXPECT_EQ(loader.stats().submitted, 0u);
    const TileKey bad_painting = {3, 0, 0, 0};
    EXPECT_THROW(loader.submit(&bad_painting, 1), InvalidArgument);
}

// Several threads submit, poll, read stats and finally close one loader at the same time
// (as Python threads may): every tile is delivered exactly once, to one caller, with the
// bytes a direct read of the pack gives; the backlog counter ends at zero and close() returns.
// Run under ThreadSanitizer by `make sanitize` (ctest -R SeveralCallers).
TEST_P(LoaderTest, SeveralCallersGetEveryTileOnceWithTheRightBytes) {
    const auto [mode, threads] = GetParam();
    TilePack pack(dir_.string());
    LoaderOptions o;
    o.queue_capacity = 8;  // tiny: the backlog is shared by the callers
    o.pool_tiles = 4;
    TileLoader loader(pack, mode, threads, o);
    const auto keys = all_keys(pack);
    constexpr int kCallers = 4, kCopies = 3;
    const std::size_t expected = keys.size() * kCopies * kCallers;
    std::atomic<std::size_t> delivered{0};
    std::vector<std::vector<std::pair<TileKey, std::string>>> got(kCallers);
    std::vector<std::thread> callers;
    for (int c = 0; c < kCallers; ++c)
        callers.emplace_back([&, c] {
            for (int copy = 0; copy < kCopies; ++copy)
                for (std::size_t i = 0; i < keys.size(); i += 7)  // batches of up to 7
                    loader.submit(keys.data() + i, std::min<std::size_t>(7, keys.size() - i));
            std::vector<LoadedTile> batch;
            const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
            while (delivered.load() < expected && std::chrono::steady_clock::now() < deadline) {
                batch.clear();
                if (loader.poll(batch, 3) == 0) std::this_thread::yield();
                for (auto& r : batch) {
                    ASSERT_GE(r.buffer, 0) << r.error;
                    got[c].emplace_back(r.key, std::string(reinterpret_cast<const char*>(loader.data(r.buffer)),
                                                           loader.tile_bytes()));
                    loader.release(r.buffer);
                    delivered.fetch_add(1);
                }
                (void)loader.stats();
            }
        });
    for (auto& t : callers) t.join();
    std::thread closer([&] { loader.close(); });  // from another thread than the callers
    closer.join();
    EXPECT_TRUE(loader.closed());
    std::map<std::uint64_t, int> seen;
    std::vector<std::uint8_t> direct(pack.tile_bytes());
    std::size_t total = 0;
    for (const auto& per_caller : got)
        for (const auto& [key, bytes] : per_caller) {
            ++seen[key.packed()];
            ++total;
            pack.read_tile(key.painting, key.level, key.tx, key.ty, direct.data());
            ASSERT_EQ(std::memcmp(bytes.data(), direct.data(), direct.size()), 0);
        }
    EXPECT_EQ(total, expected);
    EXPECT_EQ(seen.size(), keys.size());
    for (const auto& [k, n] : seen) EXPECT_EQ(n, kCopies * kCallers);
    const LoaderStats s = loader.stats();
    EXPECT_EQ(s.submitted, expected);
    EXPECT_EQ(s.loaded, expected);
    EXPECT_EQ(s.backlog, 0u);
    EXPECT_EQ(s.cancelled, 0u);
}

INSTANTIATE_TEST_SUITE_P(Modes, LoaderTest,
                         ::testing::Values(std::make_tuple(LoaderMode::LockFree, 1u),
                                           std::make_tuple(LoaderMode::LockFree, 2u),
                                           std::make_tuple(LoaderMode::Locked, 1u),
                                           std::make_tuple(LoaderMode::Locked, 3u)));

// The repeat filter and the request-processing methods (basic, flag array, hash, async) and
// visibility lists against a brute-force reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "common/error.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "views/request_hash.h"
#include "views/request_processing.h"
#include "views/residency.h"
#include "views/random_feedback.h"

using namespace gigascroll;

namespace {

ResidentSet random_residency(const std::vector<PaintingGeometry>& paintings, unsigned seed) {
    ResidentSet r(paintings);
    std::mt19937_64 rng(seed);
    for (std::uint32_t p = 0; p < paintings.size(); ++p)
        for (std::uint32_t l = 0; l < paintings[p].levels(); ++l)
            for (std::uint32_t y = 0; y < paintings[p].tiles_y(l); ++y)
                for (std::uint32_t x = 0; x < paintings[p].tiles_x(l); ++x)
                    if (rng() % 3 == 0) r.insert(pack_request(p, l, x, y));
    return r;
}

}  // namespace

// The block-skipping scan marks exactly what key-by-key fresh() marks, in the same order:
// long runs of one key (skipped eight at a time), runs of kNoRequest, short runs, run ends
// at every offset within a block of eight.
TEST(RequestProcessing, RepeatFilterScanEqualsKeyByKey) {
    std::mt19937 rng(31);
    for (int trial = 0; trial < 50; ++trial) {
        std::vector<std::uint64_t> keys;
        while (keys.size() < 5000) {
            const std::size_t run = 1 + rng() % (rng() % 4 == 0 ? 100 : 9);
            const std::uint64_t key = rng() % 5 == 0 ? kNoRequest : pack_request(0, rng() % 3, rng() % 40, 0);
            keys.insert(keys.end(), run, key);
        }
        const std::size_t n = keys.size() - rng() % 8;
        std::vector<std::uint64_t> one_by_one, scanned;
        RepeatFilter a, b;
        for (std::size_t i = 0; i < n; ++i)
            if (a.fresh(keys[i])) one_by_one.push_back(keys[i]);
        // In two calls, as parallel chunks and buffer boundaries split a scan.
        const std::size_t cut = rng() % n;
        b.scan(keys.data(), cut, [&](std::uint64_t k) { scanned.push_back(k); });
        b.scan(keys.data() + cut, n - cut, [&](std::uint64_t k) { scanned.push_back(k); });
        ASSERT_EQ(scanned, one_by_one) << "trial " << trial;
        // And nothing distinct is lost: the filter only drops repeats.
        std::set<std::uint64_t> all(keys.begin(), keys.begin() + n);
        all.erase(kNoRequest);
        EXPECT_EQ(std::set<std::uint64_t>(scanned.begin(), scanned.end()), all);
    }
}

TEST(RequestProcessing, FourMethodsAgree) {
    const auto paintings = small_paintings();
    const ResidentSet resident = random_residency(paintings, 5);
    FlagArrayProcessor flags(paintings, 2);
    HashProcessor hash(20, 2);  // big table: no collisions expected
    AsyncProcessor async;
    BasicProcessor basic;
    for (unsigned frame = 1; frame <= 5; ++frame) {
        const auto buffers = random_buffers(paintings, 3, 20000 + 1000 * frame, 300, frame);
        const auto views = spans(buffers);
        const auto ref = distinct(buffers);
        const RequestSets b = basic.process(views, resident);
        ASSERT_EQ(sorted(b.requests), std::vector<std::uint64_t>(ref.begin(), ref.end()));
        // Independent responses and commands: straight from the residency set.
        std::vector<std::uint64_t> commands;
        std::map<std::uint64_t, std::uint64_t> resp;
        for (auto k : ref) {
            resp[k] = ancestor_request(k, resident.resident_level(k));
            if (resp[k] != k) commands.push_back(k);
        }
        async.submit(views, frame);
        const auto done = async.drain(resident);
        ASSERT_EQ(done.size(), 1u);
        EXPECT_EQ(done[0].frame, frame);
        for (const RequestSets& s : {b, flags.process(views, resident),
                                     hash.process(views, resident, frame), done[0].sets}) {
            EXPECT_EQ(sorted(s.requests), std::vector<std::uint64_t>(ref.begin(), ref.end()));
            EXPECT_EQ(sorted(s.commands), commands);
            ASSERT_EQ(s.responses.size(), s.requests.size());
            for (std::size_t i = 0; i < s.requests.size(); ++i)
                EXPECT_EQ(s.responses[i], resp[s.requests[i]]);
        }
    }
}

TEST(RequestProcessing, BadKeysThrowAndLeaveProcessorsUsable) {
    const auto paintings = small_paintings();
    const ResidentSet resident(paintings);
    const std::vector<std::vector<std::uint64_t>> bad{{pack_request(0, 0, 1, 1), pack_request(7, 0, 0, 0)}};
    const std::vector<std::vector<std::uint64_t>> good{{pack_request(0, 0, 1, 1)}};
    FlagArrayProcessor flags(paintings, 2);
    HashProcessor hash(10, 2);
    BasicProcessor basic;
    VisibilityLists vis(paintings, 2);
    EXPECT_THROW(flags.process(spans(bad), resident), InvalidArgument);
    EXPECT_THROW(hash.process(spans(bad), resident, 1), InvalidArgument);
    EXPECT_THROW(basic.process(spans(bad), resident), InvalidArgument);
    EXPECT_THROW(vis.process(spans(bad)), InvalidArgument);
    EXPECT_EQ(flags.process(spans(good), resident).requests, good[0]);
    EXPECT_EQ(hash.process(spans(good), resident, 2).requests, good[0]);
    EXPECT_EQ(vis.process(spans(good)).alive, good[0]);
    EXPECT_THROW(HashProcessor(40), InvalidArgument);
}

TEST(VisibilityLists, AliveAndRemoveAgainstSetDifference) {
    const auto paintings = small_paintings();
    VisibilityLists vis(paintings, 2);
    std::set<std::uint64_t> previous;
    for (unsigned frame = 0; frame < 4; ++frame) {
        const auto buffers = random_buffers(paintings, 2, 5000, 120, 100 + frame % 2);
        const auto now = distinct(buffers);
        const auto lists = vis.process(spans(buffers));
        EXPECT_EQ(sorted(lists.alive), std::vector<std::uint64_t>(now.begin(), now.end()));
        std::vector<std::uint64_t> removed;
        std::set_difference(previous.begin(), previous.end(), now.begin(), now.end(),
                            std::back_inserter(removed));
        EXPECT_EQ(sorted(lists.remove), removed);
        previous = now;
    }
}

// One processor shared by threads (each processing frames of its own): every call returns
// what a processor of its own returns; the flag arrays and the hash table are one frame's,
// so the calls take turns (they used to mark into each other's frames; TSan checks the lock
// under `make sanitize`).
TEST(RequestProcessing, OneProcessorSharedByThreadsGivesTheSerialSets) {
    const auto paintings = small_paintings();
    const ResidentSet resident = random_residency(paintings, 9);
    constexpr int kThreads = 4, kFrames = 6;
    std::vector<std::vector<std::vector<std::uint64_t>>> buffers;  // per thread
    for (int t = 0; t < kThreads; ++t) buffers.push_back(random_buffers(paintings, 2, 3000, 200, 40 + t));
    auto requests = [](const RequestSets& s) { return sorted(s.requests); };
    FlagArrayProcessor flags(paintings, 1);
    HashProcessor hash(20, 1);
    VisibilityLists vis(paintings, 1);
    std::vector<int> wrong(kThreads, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([&, t] {
            const auto views = spans(buffers[std::size_t(t)]);
            const auto d = distinct(buffers[std::size_t(t)]);
            const std::vector<std::uint64_t> want(d.begin(), d.end());
            for (int f = 0; f < kFrames; ++f) {
                wrong[std::size_t(t)] += requests(flags.process(views, resident)) != want;
                wrong[std::size_t(t)] += requests(hash.process(views, resident, 1 + std::uint64_t(f))) != want;
                wrong[std::size_t(t)] += sorted(vis.process(views).alive) != want;
            }
        });
    for (std::thread& th : threads) th.join();
    EXPECT_EQ(wrong, std::vector<int>(kThreads, 0));
}

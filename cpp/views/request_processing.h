// Request processing: from this frame's feedback buffers (both eyes and the magnifier) to
// the request-response set and the load-command set. Four methods, one result:
//   BasicProcessor      (Barrett)      one thread scans every pixel into a hash set;
//   AsyncProcessor      (Unreal SVT)   a worker thread deduplicates in the background;
//   FlagArrayProcessor  (Hollemeersch) parallel marking into one flag per tile, then a
//                                      parallel compaction scan over all flags;
//   HashProcessor       (VT-mobile-VR)     request_hash.h.
// The response of a request is looked up once per distinct request, after deduplication;
// a GPU does it per pixel, with the same result.
#pragma once
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "common/parallel.h"
#include "pack/tile_key.h"
#include "views/residency.h"

namespace gigascroll {

using FeedbackBuffer = std::span<const std::uint64_t>;  // kNoRequest pixels are skipped

struct RequestSets {
    std::vector<std::uint64_t> requests;   // distinct requests
    std::vector<std::uint64_t> responses;  // responses[i] answers requests[i]
    std::vector<std::uint64_t> commands;   // requests whose response is not the request
};

// Fills responses and commands for `requests` (already distinct).
void resolve_requests(RequestSets& sets, const ResidencyLookup& lookup);

// Drops keys this thread saw recently before they reach a shared structure: the previous
// key (neighbouring pixels of a row usually see the same tile) and a 256-entry direct-mapped
// cache of recent keys (the rows above saw the same tiles). It only ever drops repeats, so
// every method stays exact; all four methods scan through one, so they differ only in the
// structure that deduplicates what passes.
class RepeatFilter {
public:
    RepeatFilter() { recent_.fill(kNoRequest); }
    // False for kNoRequest and for a key seen recently.
    bool fresh(std::uint64_t key) {
        if (key == last_) return false;  // also kNoRequest: last_ starts there
        last_ = key;
        if (key == kNoRequest) return false;
        std::uint64_t& slot = recent_[(key * 0x9E3779B97F4A7C15ull) >> 56];
        if (slot == key) return false;
        slot = key;
        return true;
    }

    // Calls mark(key) for every fresh key of keys[0, n). Feedback rows repeat one key for
    // long stretches (the magnifier's 262k pixels hold a dozen tiles), so blocks of eight
    // keys all equal to the last one are skipped in one vectorised comparison.
    template <typename Mark>
    void scan(const std::uint64_t* keys, std::size_t n, Mark&& mark) {
        std::size_t i = 0;
        while (i < n) {
            for (; i + 8 <= n; i += 8) {
                std::uint64_t differ = 0;
                for (std::size_t k = 0; k < 8; ++k) differ |= keys[i + k] ^ last_;
                if (differ) break;
            }
            const std::size_t stop = std::min(n, i + 8);
            for (; i < stop; ++i)
                if (fresh(keys[i])) mark(keys[i]);
        }
    }

private:
    std::array<std::uint64_t, 256> recent_;
    std::uint64_t last_ = kNoRequest;
};

// Calls mark(key) for every requesting pixel of every buffer, from `threads` threads (one
// parallel loop over all buffers together), after each thread's RepeatFilter.
template <typename Mark>
void for_each_request(std::span<const FeedbackBuffer> buffers, unsigned threads, Mark&& mark) {
    std::vector<std::size_t> start{0};
    for (const auto& b : buffers) start.push_back(start.back() + b.size());
    parallel_for(start.back(), 16384, [&](std::size_t begin, std::size_t end) {
        std::size_t buf = std::upper_bound(start.begin(), start.end(), begin) - start.begin() - 1;
        RepeatFilter filter;
        for (std::size_t i = begin; i < end;) {
            while (i >= start[buf + 1]) ++buf;
            const std::size_t stop = std::min(end, start[buf + 1]);
            filter.scan(buffers[buf].data() + (i - start[buf]), stop - i, mark);
            i = stop;
        }
    }, threads);
}

class BasicProcessor {
public:
    RequestSets process(std::span<const FeedbackBuffer> buffers, const ResidencyLookup& lookup);
};

class FlagArrayProcessor {
public:
    explicit FlagArrayProcessor(std::vector<PaintingGeometry> paintings, unsigned threads = 0);
    FlagArrayProcessor(const FlagArrayProcessor&) = delete;
    FlagArrayProcessor& operator=(const FlagArrayProcessor&) = delete;
    RequestSets process(std::span<const FeedbackBuffer> buffers, const ResidencyLookup& lookup);
    std::uint64_t flag_count() const { return index_.size(); }

private:
    TileIndex index_;
    unsigned threads_;
    // Held by process(): the flags are one frame's, so calls from several threads take turns.
    std::mutex mutex_;
    // One flag per tile. Marking stores 1 through std::atomic_ref (relaxed) from many
    // threads; the compaction scan runs after the marking threads joined, which orders it
    // after them, and reads eight flags per word to skip empty stretches.
    std::vector<std::uint8_t> flags_;
};

// The Unreal SVT way: submit() copies the buffers and returns at once; a worker thread
// deduplicates them; poll() hands back finished frames, resolved against the page table at
// poll time on the caller's thread (so the page table is never read concurrently with its
// updates). The latency of a result in frames is poll frame - submit frame, measured by the
// caller.
class AsyncProcessor {
public:
    AsyncProcessor();
    ~AsyncProcessor();
    AsyncProcessor(const AsyncProcessor&) = delete;
    AsyncProcessor& operator=(const AsyncProcessor&) = delete;

    void submit(std::span<const FeedbackBuffer> buffers, std::uint64_t frame);
    struct Result {
        std::uint64_t frame;  // the frame whose feedback this is
        double seconds;       // from submit() until the worker finished it
        RequestSets sets;
    };
    // Every result finished since the last poll, oldest first.
    std::vector<Result> poll(const ResidencyLookup& lookup);
    // Blocks until every submitted frame is finished, then polls.
    std::vector<Result> drain(const ResidencyLookup& lookup);
    std::size_t pending() const;

private:
    struct Job {
        std::uint64_t frame;
        std::chrono::steady_clock::time_point submitted;
        std::vector<std::uint64_t> pixels;
    };
    void run();

    mutable std::mutex mutex_;
    std::condition_variable wake_, idle_;
    std::deque<Job> jobs_;
    std::vector<Result> done_;
    bool busy_ = false, stop_ = false;
    std::thread worker_;
};

// Vulkan-SVT: alive and remove lists from this frame's and the previous frame's visibility,
// over a flag array of every tile (alive = visible now; remove = visible last frame only).
class VisibilityLists {
public:
    explicit VisibilityLists(std::vector<PaintingGeometry> paintings, unsigned threads = 0);
    VisibilityLists(const VisibilityLists&) = delete;
    VisibilityLists& operator=(const VisibilityLists&) = delete;
    struct Lists {
        std::vector<std::uint64_t> alive, remove;
    };
    Lists process(std::span<const FeedbackBuffer> buffers);

private:
    TileIndex index_;
    unsigned threads_;
    std::mutex mutex_;  // held by process(): one frame at a time against the previous one
    std::vector<std::uint8_t> current_;  // marked like FlagArrayProcessor's flags
    std::vector<std::uint8_t> previous_;
};

}  // namespace gigascroll

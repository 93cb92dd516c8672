#include "views/request_processing.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <unordered_set>


namespace gigascroll {

namespace {
constexpr std::size_t kFlagChunk = 1 << 16;

// Marks every requested tile in `flags` (clearing them all again if a key is invalid).
void mark_flags(const TileIndex& index, std::vector<std::uint8_t>& flags,
                std::span<const FeedbackBuffer> buffers, unsigned threads) {
    try {
        for_each_request(buffers, threads, [&](std::uint64_t key) {
            std::atomic_ref<std::uint8_t>(flags[index.index(key)]).store(1, std::memory_order_relaxed);
        });
    } catch (...) {
        std::fill(flags.begin(), flags.end(), 0);
        throw;
    }
}

// Calls f(i) for every i in [b, e) with a[i] | c[i] != 0, eight bytes at a time.
template <typename F>
void for_each_set(const std::uint8_t* a, const std::uint8_t* c, std::size_t b, std::size_t e, F&& f) {
    std::size_t i = b;
    for (; i + 8 <= e; i += 8) {
        std::uint64_t wa, wc = 0;
        std::memcpy(&wa, a + i, 8);
        if (c) std::memcpy(&wc, c + i, 8);
        if ((wa | wc) == 0) continue;
        for (std::size_t j = i; j < i + 8; ++j)
            if (a[j] | (c ? c[j] : 0)) f(j);
    }
    for (; i < e; ++i)
        if (a[i] | (c ? c[i] : 0)) f(i);
}
}  // namespace

void resolve_requests(RequestSets& sets, const ResidencyLookup& lookup) {
    sets.responses.resize(sets.requests.size());
    sets.commands.clear();
    for (std::size_t i = 0; i < sets.requests.size(); ++i) {
        const std::uint64_t r = sets.requests[i], s = response_of(lookup, r);
        sets.responses[i] = s;
        if (s != r) sets.commands.push_back(r);
    }
}

RequestSets BasicProcessor::process(std::span<const FeedbackBuffer> buffers,
                                    const ResidencyLookup& lookup) {
    std::unordered_set<std::uint64_t> seen;
    RepeatFilter filter;
    for (const FeedbackBuffer& buffer : buffers)
        filter.scan(buffer.data(), buffer.size(), [&](std::uint64_t key) { seen.insert(key); });
    RequestSets sets;
    sets.requests.assign(seen.begin(), seen.end());
    resolve_requests(sets, lookup);
    return sets;
}

FlagArrayProcessor::FlagArrayProcessor(std::vector<PaintingGeometry> paintings, unsigned threads)
    : index_(std::move(paintings)), threads_(threads), flags_(index_.size()) {}

RequestSets FlagArrayProcessor::process(std::span<const FeedbackBuffer> buffers,
                                        const ResidencyLookup& lookup) {
    const std::scoped_lock lock(mutex_);
    mark_flags(index_, flags_, buffers, threads_);
    // Compaction: each chunk collects (and clears) its set flags; chunks concatenate in order.
    const std::size_t chunks = (flags_.size() + kFlagChunk - 1) / kFlagChunk;
    std::vector<std::vector<std::uint64_t>> found(chunks);
    parallel_for(flags_.size(), kFlagChunk, [&](std::size_t b, std::size_t e) {
        auto& out = found[b / kFlagChunk];
        for_each_set(flags_.data(), nullptr, b, e, [&](std::size_t i) {
            flags_[i] = 0;
            out.push_back(index_.key(i));
        });
    }, threads_);
    RequestSets sets;
    for (auto& f : found) sets.requests.insert(sets.requests.end(), f.begin(), f.end());
    resolve_requests(sets, lookup);
    return sets;
}

AsyncProcessor::AsyncProcessor() : worker_([this] { run(); }) {}

AsyncProcessor::~AsyncProcessor() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    worker_.join();
}

void AsyncProcessor::submit(std::span<const FeedbackBuffer> buffers, std::uint64_t frame) {
    Job job{frame, std::chrono::steady_clock::now(), {}};
    std::size_t n = 0;
    for (const auto& b : buffers) n += b.size();
    job.pixels.reserve(n);
    for (const auto& b : buffers) job.pixels.insert(job.pixels.end(), b.begin(), b.end());
    {
        std::lock_guard lock(mutex_);
        jobs_.push_back(std::move(job));
    }
    wake_.notify_one();
}

void AsyncProcessor::run() {
    std::unique_lock lock(mutex_);
    for (;;) {
        wake_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
        if (stop_) return;
        Job job = std::move(jobs_.front());
        jobs_.pop_front();
        busy_ = true;
        lock.unlock();
        std::unordered_set<std::uint64_t> seen;
        RepeatFilter filter;
        filter.scan(job.pixels.data(), job.pixels.size(),
                    [&](std::uint64_t key) { seen.insert(key); });
        Result result{job.frame, 0.0, {}};
        result.sets.requests.assign(seen.begin(), seen.end());
        result.seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - job.submitted).count();
        lock.lock();
        done_.push_back(std::move(result));
        busy_ = false;
        idle_.notify_all();
    }
}

std::vector<AsyncProcessor::Result> AsyncProcessor::poll(const ResidencyLookup& lookup) {
    std::vector<Result> out;
    {
        std::lock_guard lock(mutex_);
        out.swap(done_);
    }
    for (Result& r : out) resolve_requests(r.sets, lookup);
    return out;
}

std::vector<AsyncProcessor::Result> AsyncProcessor::drain(const ResidencyLookup& lookup) {
    {
        std::unique_lock lock(mutex_);
        idle_.wait(lock, [&] { return jobs_.empty() && !busy_; });
    }
    return poll(lookup);
}

std::size_t AsyncProcessor::pending() const {
    std::lock_guard lock(mutex_);
    return jobs_.size() + (busy_ ? 1 : 0);
}

VisibilityLists::VisibilityLists(std::vector<PaintingGeometry> paintings, unsigned threads)
    : index_(std::move(paintings)), threads_(threads), current_(index_.size()),
      previous_(index_.size(), 0) {}

VisibilityLists::Lists VisibilityLists::process(std::span<const FeedbackBuffer> buffers) {
    const std::scoped_lock lock(mutex_);
    mark_flags(index_, current_, buffers, threads_);
    // Vulkan-SVT's ProcessVisibility: alive if visible now, else remove if visible before;
    // then previous = current, current = 0. Per-chunk lists replace its atomic counters.
    const std::size_t chunks = (current_.size() + kFlagChunk - 1) / kFlagChunk;
    std::vector<Lists> parts(chunks);
    parallel_for(current_.size(), kFlagChunk, [&](std::size_t b, std::size_t e) {
        Lists& out = parts[b / kFlagChunk];
        for_each_set(current_.data(), previous_.data(), b, e, [&](std::size_t i) {
            const std::uint8_t now = current_[i];
            if (now)
                out.alive.push_back(index_.key(i));
            else
                out.remove.push_back(index_.key(i));
            previous_[i] = now;
            current_[i] = 0;
        });
    }, threads_);
    Lists lists;
    for (auto& p : parts) {
        lists.alive.insert(lists.alive.end(), p.alive.begin(), p.alive.end());
        lists.remove.insert(lists.remove.end(), p.remove.begin(), p.remove.end());
    }
    return lists;
}

}  // namespace gigascroll

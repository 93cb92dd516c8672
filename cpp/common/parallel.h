// A minimal parallel-for over an index range: enough for the core's embarrassingly parallel
// loops without pulling in a task scheduler.
//
// The helpers come from one process-wide pool of (cores - 1) threads created on first use:
// the frame loop makes about ten parallel calls a frame, and starting a thread per call cost
// ~30 us plus a late start of the helper. A call that finds the pool busy (another thread's
// parallel_for, or a parallel_for nested inside a helper) starts its own threads as before,
// so callers never wait for each other and nesting cannot deadlock.
#pragma once
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "common/limits.h"

namespace gigascroll {

// Number of worker threads to use when the caller passes 0. Asked once: the helper pool is
// sized from it at first use anyway, and std::thread::hardware_concurrency reads /sys on
// every call (a few percent of a small bake or still that calls parallel_for often).
inline unsigned default_threads() {
    static const unsigned all = [] {
        const unsigned n = std::thread::hardware_concurrency();
        return n == 0 ? 1u : n;
    }();
    return all;
}

namespace detail {

// The helper threads. run() hands a job to up to `helpers` of them and returns while they
// work; finish() waits for those that took it. All shared state is guarded by mutex_ (the
// job itself synchronises through its own atomics), which keeps the pool
// ThreadSanitizer-clean.
class HelperPool {
public:
    using Job = void (*)(void*);

    static HelperPool& instance() {
        // Leaked on purpose: helpers are detached and idle at exit, and a static destructor
        // joining threads at unload time is a classic shutdown hang. After fork() the child
        // has no helpers, so it starts a fresh pool.
        static std::once_flag once;
        std::call_once(once, [] { pthread_atfork(nullptr, nullptr, [] { current() = nullptr; }); });
        std::lock_guard lock(create_mutex());
        if (!current()) current() = new HelperPool(default_threads() - 1);
        return *current();
    }

    // Starts job(context) on min(helpers, pool size) helpers and returns that number; 0
    // (nothing started, no finish() due) when the pool is already running a job.
    unsigned run(unsigned helpers, Job job, void* context) {
        std::lock_guard lock(mutex_);
        if (busy_ || size_ == 0 || helpers == 0) return 0;
        busy_ = true;
        job_ = job, context_ = context;
        wanted_ = std::min(helpers, size_);
        taken_ = finished_ = 0;
        ++generation_;
        wake_.notify_all();
        return wanted_;
    }

    // Waits until the helpers of the last run() that took the job returned from it. Called
    // once the caller's own share is done, i.e. when no work is left to hand out: a helper
    // that has not woken up yet is no longer wanted (it skips the job when it wakes) instead
    // of being waited for; on a loaded machine its wake-up alone took longer than a small job.
    void finish() {
        std::unique_lock lock(mutex_);
        wanted_ = taken_;
        done_.wait(lock, [&] { return finished_ == wanted_; });
        busy_ = false;
    }

private:
    explicit HelperPool(unsigned size) : size_(size) {
        for (unsigned i = 0; i < size; ++i) std::thread([this] { loop(); }).detach();
    }

    static HelperPool*& current() {
        static HelperPool* pool = nullptr;
        return pool;
    }
    static std::mutex& create_mutex() {
        static std::mutex m;
        return m;
    }

    void loop() {
        std::uint64_t seen = 0;
        std::unique_lock lock(mutex_);
        for (;;) {
            wake_.wait(lock, [&] { return generation_ != seen; });
            seen = generation_;
            if (taken_ == wanted_) continue;  // enough helpers took this job already
            ++taken_;
            const Job job = job_;
            void* const context = context_;
            lock.unlock();
            job(context);
            lock.lock();
            if (++finished_ == wanted_) done_.notify_all();
        }
    }

    const unsigned size_;
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    bool busy_ = false;
    Job job_ = nullptr;
    void* context_ = nullptr;
    unsigned wanted_ = 0, taken_ = 0, finished_ = 0;
    std::uint64_t generation_ = 0;
};

}  // namespace detail

// Calls body(begin, end) on chunks of [0, n) from `threads` threads (0 = all cores; more than
// kMaxThreads is an InvalidArgument), the calling thread included. Chunks are handed out
// dynamically so uneven work balances. The
// first exception thrown by any chunk is rethrown on the calling thread after all chunks
// stopped.
template <typename Body>
void parallel_for(std::size_t n, std::size_t chunk, Body&& body, unsigned threads = 0) {
    require_threads(threads, "parallel work");  // a huge count would try to start that many threads
    if (n == 0) return;
    if (threads == 0) threads = default_threads();
    chunk = std::max<std::size_t>(chunk, 1);
    const std::size_t chunks = (n + chunk - 1) / chunk;
    threads = static_cast<unsigned>(std::min<std::size_t>(threads, chunks));
    if (threads <= 1) {
        body(std::size_t(0), n);
        return;
    }
    std::atomic<std::size_t> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    auto worker = [&] {
        for (;;) {
            const std::size_t c = next.fetch_add(1, std::memory_order_relaxed);
            if (c >= chunks) return;
            try {
                body(c * chunk, std::min(n, (c + 1) * chunk));
            } catch (...) {
                std::lock_guard lock(error_mutex);
                if (!error) error = std::current_exception();
                next.store(chunks, std::memory_order_relaxed);
            }
        }
    };
    auto& pool = detail::HelperPool::instance();
    auto run_worker = [](void* w) { (*static_cast<decltype(worker)*>(w))(); };
    const unsigned pooled = pool.run(threads - 1, run_worker, &worker);
    std::vector<std::thread> extra;  // what the pool could not provide
    extra.reserve(threads - 1 - pooled);
    for (unsigned t = 1 + pooled; t < threads; ++t) extra.emplace_back(worker);
    worker();
    for (auto& th : extra) th.join();
    if (pooled) pool.finish();
    if (error) std::rethrow_exception(error);
}

// Two passes over the same chunks [0, chunks), where second(c) may start only once first(c - 1),
// first(c) and first(c + 1) (those that exist) are done: a wavefront, for a second pass that
// reads what the first wrote on and beside its chunk (the right eye's rows read the left
// eye's claims). Both passes' chunks are handed out in one sequence, second(c) kLag chunks
// after first(c) (kLag >= 2, so a second-pass chunk rarely waits), on `threads` threads as
// parallel_for. A waiting chunk waits only for chunks handed out before it, which never wait
// themselves: no deadlock. A first-pass chunk that throws still counts as done, so nobody
// waits for it forever; the first exception is rethrown once every started chunk stopped.
template <typename First, typename Second>
void parallel_wavefront(std::size_t chunks, First&& first, Second&& second, unsigned threads = 0) {
    constexpr std::size_t kLag = 3;
    std::vector<std::atomic<std::uint8_t>> done(chunks);
    for (auto& d : done) d.store(0, std::memory_order_relaxed);
    // Task t: first-pass chunks 0 .. kLag - 1, then alternately first-pass chunk c and
    // second-pass chunk c - kLag, then the second pass's last kLag chunks.
    auto task = [&](std::size_t t, bool& is_second) {
        if (t < kLag || chunks <= kLag) {
            is_second = t >= chunks;
            return is_second ? t - chunks : t;
        }
        const std::size_t u = t - kLag;
        if (u < 2 * (chunks - kLag)) {
            is_second = u % 2 == 1;
            return is_second ? u / 2 : kLag + u / 2;
        }
        is_second = true;
        return chunks - kLag + (u - 2 * (chunks - kLag));
    };
    parallel_for(2 * chunks, 1, [&](std::size_t t0, std::size_t t1) {
        for (std::size_t t = t0; t < t1; ++t) {
            bool is_second = false;
            const std::size_t c = task(t, is_second);
            if (!is_second) {
                try {
                    first(c);
                } catch (...) {
                    done[c].store(1, std::memory_order_release);
                    throw;
                }
                done[c].store(1, std::memory_order_release);
                continue;
            }
            for (std::size_t d = c == 0 ? 0 : c - 1; d <= std::min(chunks - 1, c + 1); ++d)
                for (unsigned spins = 0; !done[d].load(std::memory_order_acquire); ++spins) {
                    if (spins < 64) continue;  // a short spin first: the wait is usually brief
                    std::this_thread::yield();
                }
            second(c);
        }
    }, threads);
}

}  // namespace gigascroll

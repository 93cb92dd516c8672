// A minimal parallel-for over an index range on std::threads: enough for the core's
// embarrassingly parallel loops without pulling in a task scheduler.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace gigascroll {

// Number of worker threads to use when the caller passes 0.
inline unsigned default_threads() {
    unsigned n = std::thread::hardware_concurrency();
    return n == 0 ? 1 : n;
}

// Calls body(begin, end) on chunks of [0, n) from `threads` threads (0 = all cores).
// Chunks are handed out dynamically so uneven work balances. The first exception
// thrown by any chunk is rethrown on the calling thread after all threads joined.
template <typename Body>
void parallel_for(std::size_t n, std::size_t chunk, Body&& body, unsigned threads = 0) {
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
    std::vector<std::thread> pool;
    pool.reserve(threads - 1);
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& th : pool) th.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace gigascroll

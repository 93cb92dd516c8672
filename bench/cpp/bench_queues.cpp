// Queue microbenchmarks: throughput (items/s) and round-trip latency of our SPSC and MPSC
// queues against boost::lockfree, moodycamel and the mutex queue, all in one run so the
// ratios compare like with like. Elements are 8-byte integers; every queue holds 4096.
#include <benchmark/benchmark.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include <boost/lockfree/queue.hpp>
#include <boost/lockfree/spsc_queue.hpp>
#include <concurrentqueue/concurrentqueue.h>
#include <readerwriterqueue/readerwriterqueue.h>

#include "concurrency/locked_queue.h"
#include "concurrency/mpsc_queue.h"
#include "concurrency/spsc_queue.h"

using Item = std::uint64_t;

// The spin-wait hint every harness loop uses on a failed pop (same for every queue).
static inline void spin_pause() { __builtin_ia32_pause(); }
constexpr std::size_t kCapacity = 4096;
constexpr std::size_t kItems = 1 << 20;

// A uniform face over every queue: make(), push(), pop().
template <typename Q>
struct Ops {
    static auto make() { return std::make_unique<Q>(kCapacity); }
    static bool push(Q& q, Item v) { return q.try_push(v); }
    static bool pop(Q& q, Item& v) { return q.try_pop(v); }
};
using BoostSpsc = boost::lockfree::spsc_queue<Item, boost::lockfree::capacity<kCapacity>>;
template <>
struct Ops<BoostSpsc> {
    static auto make() { return std::make_unique<BoostSpsc>(); }
    static bool push(BoostSpsc& q, Item v) { return q.push(v); }
    static bool pop(BoostSpsc& q, Item& v) { return q.pop(v); }
};
using BoostQueue = boost::lockfree::queue<Item, boost::lockfree::capacity<kCapacity - 2>>;
template <>
struct Ops<BoostQueue> {
    static auto make() { return std::make_unique<BoostQueue>(); }
    static bool push(BoostQueue& q, Item v) { return q.bounded_push(v); }
    static bool pop(BoostQueue& q, Item& v) { return q.pop(v); }
};
using RWQueue = moodycamel::ReaderWriterQueue<Item>;
template <>
struct Ops<RWQueue> {
    static auto make() { return std::make_unique<RWQueue>(kCapacity); }
    static bool push(RWQueue& q, Item v) { return q.try_enqueue(v); }  // never allocates
    static bool pop(RWQueue& q, Item& v) { return q.try_dequeue(v); }
};
using CQueue = moodycamel::ConcurrentQueue<Item>;
template <>
struct Ops<CQueue> {
    static auto make() { return std::make_unique<CQueue>(kCapacity); }
    static bool push(CQueue& q, Item v) { return q.try_enqueue(v); }
    static bool pop(CQueue& q, Item& v) { return q.try_dequeue(v); }
};

using OurSpsc = gigascroll::SpscQueue<Item>;
using OurMpsc = gigascroll::MpscQueue<Item>;
using Locked = gigascroll::LockedQueue<Item>;

// `producers` threads push kItems in total one by one; this thread pops them.
template <typename Q>
static void BM_Throughput(benchmark::State& state) {
    const int producers = static_cast<int>(state.range(0));
    for (auto _ : state) {
        auto q = Ops<Q>::make();
        std::vector<std::thread> threads;
        const std::size_t per = kItems / producers;
        for (int p = 0; p < producers; ++p)
            threads.emplace_back([&q, per] {
                for (std::size_t i = 0; i < per; ++i)
                    while (!Ops<Q>::push(*q, i)) std::this_thread::yield();
            });
        Item v, sum = 0;
        for (std::size_t got = 0; got < per * producers;) {
            if (Ops<Q>::pop(*q, v)) {
                sum += v;
                ++got;
            } else {
                spin_pause();  // an empty queue: let the producer's line settle
            }
        }
        for (auto& t : threads) t.join();
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kItems / producers * producers));
}

// Same with our batch operations (64 items per call on both sides).
template <typename Q>
static void BM_ThroughputBatch(benchmark::State& state) {
    const int producers = static_cast<int>(state.range(0));
    for (auto _ : state) {
        Q q(kCapacity);
        std::vector<std::thread> threads;
        const std::size_t per = kItems / producers;
        for (int p = 0; p < producers; ++p)
            threads.emplace_back([&q, per] {
                Item batch[64];
                for (std::size_t i = 0; i < per;) {
                    const std::size_t k = std::min<std::size_t>(64, per - i);
                    for (std::size_t j = 0; j < k; ++j) batch[j] = i + j;
                    const std::size_t n = q.try_push_batch(batch, k);
                    i += n;
                    if (n == 0) std::this_thread::yield();
                }
            });
        Item out[64], sum = 0;
        for (std::size_t got = 0; got < per * producers;) {
            const std::size_t n = q.try_pop_batch(out, 64);
            for (std::size_t j = 0; j < n; ++j) sum += out[j];
            got += n;
        }
        for (auto& t : threads) t.join();
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kItems / producers * producers));
}

// Round trip: this thread sends a value through one queue, an echo thread returns it
// through a second one. Reported time per item is the round-trip latency.
template <typename Q>
static void BM_RoundTrip(benchmark::State& state) {
    auto ping = Ops<Q>::make();
    auto pong = Ops<Q>::make();
    std::atomic<bool> stop{false};
    std::thread echo([&] {
        Item v;
        while (!stop.load(std::memory_order_relaxed))
            if (Ops<Q>::pop(*ping, v))
                while (!Ops<Q>::push(*pong, v)) {
                }
    });
    Item v = 0;
    for (auto _ : state) {
        while (!Ops<Q>::push(*ping, v)) {
        }
        while (!Ops<Q>::pop(*pong, v)) {
        }
        ++v;
    }
    stop.store(true);
    echo.join();
}

#define QUEUE_BENCH(Q, P) \
    BENCHMARK_TEMPLATE(BM_Throughput, Q)->Arg(P)->Iterations(8)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime()->Unit(benchmark::kMillisecond)

// SPSC: one producer.
QUEUE_BENCH(OurSpsc, 1);
BENCHMARK_TEMPLATE(BM_ThroughputBatch, OurSpsc)->Arg(1)->Iterations(8)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime()->Unit(benchmark::kMillisecond);
QUEUE_BENCH(BoostSpsc, 1);
QUEUE_BENCH(RWQueue, 1);
QUEUE_BENCH(OurMpsc, 1);
QUEUE_BENCH(BoostQueue, 1);
QUEUE_BENCH(CQueue, 1);
QUEUE_BENCH(Locked, 1);
// MPSC: two producers (the machine has two cores; the consumer shares one).
QUEUE_BENCH(OurMpsc, 2);
BENCHMARK_TEMPLATE(BM_ThroughputBatch, OurMpsc)->Arg(2)->Iterations(8)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime()->Unit(benchmark::kMillisecond);
QUEUE_BENCH(BoostQueue, 2);
QUEUE_BENCH(CQueue, 2);
QUEUE_BENCH(Locked, 2);

BENCHMARK_TEMPLATE(BM_RoundTrip, OurSpsc)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, BoostSpsc)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, RWQueue)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, OurMpsc)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, BoostQueue)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, CQueue)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK_TEMPLATE(BM_RoundTrip, Locked)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();

BENCHMARK_MAIN();

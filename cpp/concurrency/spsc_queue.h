// Bounded single-producer single-consumer ring queue (after rigtorp's SPSCQueue).
//
// Memory ordering: the producer owns `tail_`, the consumer owns `head_`. The producer
// constructs an element in its slot, then publishes it with tail_.store(release); the
// consumer reads tail_ with acquire, so the element's construction happens-before the
// consumer touches it. Symmetrically the consumer destroys the element, then frees the
// slot with head_.store(release); the producer's acquire load of head_ orders the reuse
// after the destruction. The consumer keeps a cached copy of tail_ and re-reads the
// shared atomic only when the cache says empty. The single-item push re-reads head_ every
// time (as boost::lockfree::spsc_queue does): caching it there let the producer run a full
// lap ahead and made both sides fight over the same slots, measured 2-3x slower in
// bench_queues; the batch push, which amortises the load, keeps a cached copy. head_ and
// tail_ sit on separate cache lines (no false sharing).
#pragma once
#include <atomic>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

#include "concurrency/queue_common.h"

namespace gigascroll {

template <typename T>
class SpscQueue {
public:
    // Holds up to `capacity` elements (rounded up to a power of two, at least 2).
    explicit SpscQueue(std::size_t capacity)
        : capacity_(ring_capacity(capacity)), mask_(capacity_ - 1), slots_(capacity_) {
        // The layout the memory-ordering comment relies on: the consumer's and the
        // producer's state each on a block of their own, nothing else sharing it.
        static_assert(alignof(SpscQueue) == kCacheLine);
        static_assert(offsetof(SpscQueue, head_) % kCacheLine == 0 &&
                      offsetof(SpscQueue, tail_) % kCacheLine == 0);
        static_assert(offsetof(SpscQueue, tail_) - offsetof(SpscQueue, head_) >= kCacheLine);
        static_assert(sizeof(SpscQueue) - offsetof(SpscQueue, tail_) == kCacheLine);
    }

    ~SpscQueue() {
        while (try_pop_discard()) {
        }
    }

    SpscQueue(const SpscQueue&) = delete;
    SpscQueue& operator=(const SpscQueue&) = delete;

    std::size_t capacity() const { return capacity_; }

    // Producer side.
    template <typename U>
    [[nodiscard]] bool try_push(U&& value) {
        const std::size_t tail = tail_.load(std::memory_order_relaxed);
        head_cache_ = head_.load(std::memory_order_acquire);  // keeps the batch push's copy fresh
        if (tail - head_cache_ == capacity_) return false;
        ::new (slots_[tail & mask_].ptr()) T(std::forward<U>(value));
        tail_.store(tail + 1, std::memory_order_release);
        return true;
    }

    // Moves up to n elements from [first, first + n); returns how many were pushed.
    // One release store publishes the whole batch.
    template <typename It>
    [[nodiscard]] std::size_t try_push_batch(It first, std::size_t n) {
        const std::size_t tail = tail_.load(std::memory_order_relaxed);
        std::size_t room = capacity_ - (tail - head_cache_);
        if (room < n) {
            head_cache_ = head_.load(std::memory_order_acquire);
            room = capacity_ - (tail - head_cache_);
        }
        const std::size_t k = n < room ? n : room;
        for (std::size_t i = 0; i < k; ++i, ++first)
            ::new (slots_[(tail + i) & mask_].ptr()) T(std::move(*first));
        if (k) tail_.store(tail + k, std::memory_order_release);
        return k;
    }

    // Consumer side.
    [[nodiscard]] bool try_pop(T& out) {
        const std::size_t head = head_.load(std::memory_order_relaxed);
        if (head == tail_cache_) {
            tail_cache_ = tail_.load(std::memory_order_acquire);
            if (head == tail_cache_) return false;
        }
        T* p = slots_[head & mask_].ptr();
        out = std::move(*p);
        p->~T();
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    // Moves up to max elements into out (an output iterator); returns how many.
    template <typename OutIt>
    [[nodiscard]] std::size_t try_pop_batch(OutIt out, std::size_t max) {
        const std::size_t head = head_.load(std::memory_order_relaxed);
        std::size_t avail = tail_cache_ - head;
        if (avail < max) {
            tail_cache_ = tail_.load(std::memory_order_acquire);
            avail = tail_cache_ - head;
        }
        const std::size_t k = max < avail ? max : avail;
        for (std::size_t i = 0; i < k; ++i, ++out) {
            T* p = slots_[(head + i) & mask_].ptr();
            *out = std::move(*p);
            p->~T();
        }
        if (k) head_.store(head + k, std::memory_order_release);
        return k;
    }

    // Approximate when called concurrently; exact from either side when the other is idle.
    bool empty() const {
        return tail_.load(std::memory_order_acquire) == head_.load(std::memory_order_acquire);
    }
    std::size_t size_approx() const {
        const std::size_t h = head_.load(std::memory_order_acquire);
        const std::size_t t = tail_.load(std::memory_order_acquire);
        return t - h;
    }

private:
    struct Slot {
        alignas(T) unsigned char bytes[sizeof(T)];
        T* ptr() { return std::launder(reinterpret_cast<T*>(bytes)); }
    };

    bool try_pop_discard() {
        const std::size_t head = head_.load(std::memory_order_relaxed);
        if (head == tail_.load(std::memory_order_acquire)) return false;
        slots_[head & mask_].ptr()->~T();
        head_.store(head + 1, std::memory_order_release);
        return true;
    }

    const std::size_t capacity_;
    const std::size_t mask_;
    RawSlots<Slot> slots_;
    // Consumer state: its index and its cached view of the producer's index.
    alignas(kCacheLine) std::atomic<std::size_t> head_{0};
    std::size_t tail_cache_ = 0;
    // Producer state.
    alignas(kCacheLine) std::atomic<std::size_t> tail_{0};
    std::size_t head_cache_ = 0;
    char pad_[kCacheLine - sizeof(std::size_t) * 2];
};

}  // namespace gigascroll

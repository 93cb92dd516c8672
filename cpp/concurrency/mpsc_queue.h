// Bounded multi-producer single-consumer queue: Dmitry Vyukov's bounded MPMC ring with
// per-cell sequence numbers, specialised to one consumer (the consumer's index is plain,
// it never CASes).
//
// Memory ordering: cell i of lap r has seq == pos while free for position pos, seq ==
// pos + 1 once filled. A producer claims position pos by CAS on tail_ (relaxed: the CAS
// only arbitrates between producers, the cell's seq carries the data), checks the cell is
// free with seq.load(acquire) (pairs with the consumer's release that freed it, so the
// old element's destruction happens-before the new construction), constructs the element
// and publishes it with seq.store(pos + 1, release). The consumer's acquire load of seq
// pairs with that store. Because positions are handed out in CAS order and the consumer
// pops in position order, each producer's elements come out in the order it pushed them.
//
// Progress: producers are lock-free with respect to each other; the consumer can be held
// up by a producer preempted between its CAS and its publish (it sees "empty" at that
// cell until the producer resumes). That is the usual trade of this design and harmless
// for the tile loader, where the consumer polls once per frame.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <utility>

#include "concurrency/queue_common.h"

namespace gigascroll {

template <typename T>
class MpscQueue {
public:
    explicit MpscQueue(std::size_t capacity)
        : capacity_(ring_capacity(capacity)), mask_(capacity_ - 1), cells_(capacity_) {
        for (std::size_t i = 0; i < capacity_; ++i)
            ::new (&cells_[i].seq) std::atomic<std::size_t>(i);
        // Producers' shared tail and the consumer's head each on a block of their own.
        static_assert(alignof(MpscQueue) == kCacheLine);
        static_assert(offsetof(MpscQueue, tail_) % kCacheLine == 0 &&
                      offsetof(MpscQueue, head_) % kCacheLine == 0);
        static_assert(offsetof(MpscQueue, head_) - offsetof(MpscQueue, tail_) >= kCacheLine);
        static_assert(sizeof(MpscQueue) - offsetof(MpscQueue, head_) == kCacheLine);
    }

    ~MpscQueue() {
        for (;; ++head_) {
            Cell& c = cells_[head_ & mask_];
            if (c.seq.load(std::memory_order_acquire) != head_ + 1) break;
            c.ptr()->~T();
        }
        for (std::size_t i = 0; i < capacity_; ++i) cells_[i].seq.~atomic();
    }

    MpscQueue(const MpscQueue&) = delete;
    MpscQueue& operator=(const MpscQueue&) = delete;

    std::size_t capacity() const { return capacity_; }

    // Any thread.
    template <typename U>
    [[nodiscard]] bool try_push(U&& value) {
        std::size_t pos = tail_.load(std::memory_order_relaxed);
        for (;;) {
            Cell& c = cells_[pos & mask_];
            const std::size_t seq = c.seq.load(std::memory_order_acquire);
            const auto diff = static_cast<std::intptr_t>(seq) - static_cast<std::intptr_t>(pos);
            if (diff == 0) {
                if (tail_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) {
                    ::new (c.ptr()) T(std::forward<U>(value));
                    c.seq.store(pos + 1, std::memory_order_release);
                    return true;
                }
            } else if (diff < 0) {
                return false;  // the cell still holds the element of the previous lap: full
            } else {
                pos = tail_.load(std::memory_order_relaxed);  // another producer took it
            }
        }
    }

    // Claims a run of up to n consecutive positions with one CAS. A run [pos, pos + k) is
    // free when its last cell is: the consumer frees cells in position order. The acquire
    // on that last cell also makes the frees of the earlier cells visible.
    template <typename It>
    [[nodiscard]] std::size_t try_push_batch(It first, std::size_t n) {
        if (n == 0) return 0;
        std::size_t pos = tail_.load(std::memory_order_relaxed);
        std::size_t k = n < capacity_ ? n : capacity_;
        for (;;) {
            // Free cells from pos on form a prefix (the consumer frees in position order):
            // binary-search its length, capped at k.
            std::size_t lo = 0, hi = k;
            bool raced = false;
            while (lo < hi) {
                const std::size_t mid = lo + (hi - lo + 1) / 2;
                const std::size_t last = pos + mid - 1;
                const std::size_t seq = cells_[last & mask_].seq.load(std::memory_order_acquire);
                if (seq == last) {
                    lo = mid;
                } else if (static_cast<std::intptr_t>(seq) - static_cast<std::intptr_t>(last) > 0) {
                    raced = true;  // another producer claimed it: the CAS below fails, retry
                    break;
                } else {
                    hi = mid - 1;
                }
            }
            k = raced ? 1 : lo;
            if (k == 0) return 0;
            if (tail_.compare_exchange_weak(pos, pos + k, std::memory_order_relaxed)) break;
            k = n < capacity_ ? n : capacity_;
        }
        for (std::size_t i = 0; i < k; ++i, ++first) {
            Cell& c = cells_[(pos + i) & mask_];
            // The last cell was free, so every earlier one is too: the consumer frees in
            // position order and our acquire of the last cell's seq made those frees visible.
            ::new (c.ptr()) T(std::move(*first));
            c.seq.store(pos + i + 1, std::memory_order_release);
        }
        return k;
    }

    // Consumer thread only.
    [[nodiscard]] bool try_pop(T& out) {
        Cell& c = cells_[head_ & mask_];
        if (c.seq.load(std::memory_order_acquire) != head_ + 1) return false;
        out = std::move(*c.ptr());
        c.ptr()->~T();
        c.seq.store(head_ + capacity_, std::memory_order_release);
        ++head_;
        return true;
    }

    template <typename OutIt>
    [[nodiscard]] std::size_t try_pop_batch(OutIt out, std::size_t max) {
        std::size_t k = 0;
        for (; k < max; ++k, ++out) {
            Cell& c = cells_[head_ & mask_];
            if (c.seq.load(std::memory_order_acquire) != head_ + 1) break;
            *out = std::move(*c.ptr());
            c.ptr()->~T();
            c.seq.store(head_ + capacity_, std::memory_order_release);
            ++head_;
        }
        return k;
    }

    // Consumer thread only: whether the next element is ready.
    bool empty() const {
        return cells_[head_ & mask_].seq.load(std::memory_order_acquire) != head_ + 1;
    }

private:
    struct Cell {  // unpadded: neighbours are written by the same side most of the time
        std::atomic<std::size_t> seq;
        alignas(T) unsigned char bytes[sizeof(T)];
        T* ptr() { return std::launder(reinterpret_cast<T*>(bytes)); }
    };

    const std::size_t capacity_;
    const std::size_t mask_;
    RawSlots<Cell> cells_;
    alignas(kCacheLine) std::atomic<std::size_t> tail_{0};  // shared by producers
    alignas(kCacheLine) std::size_t head_ = 0;               // consumer only
    char pad_[kCacheLine - sizeof(std::size_t)];
};

}  // namespace gigascroll

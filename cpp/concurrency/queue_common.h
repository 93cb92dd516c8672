// Shared constants of the bounded queues.
#pragma once
#include <cstddef>
#include <new>

#include "common/bits.h"

namespace gigascroll {

// Producer and consumer state live on separate blocks of this size: two 64-byte cache lines
// (x86-64 and most ARM cores), because the adjacent-line prefetcher fetches lines in pairs
// and one line apart would still share the pair (rigtorp's SPSCQueue pads the same way). The
// queues static_assert this layout.
inline constexpr std::size_t kCacheLine = 128;

// Ring size for a requested capacity: a power of two, at least 2, so index & mask wraps.
inline constexpr std::size_t ring_capacity(std::size_t n) { return next_pow2(n < 2 ? std::size_t(2) : n); }

// Uninitialised, suitably aligned storage for n ring slots; the queue constructs and
// destroys the elements in place.
template <typename Slot>
class RawSlots {
public:
    explicit RawSlots(std::size_t n)
        : data_(static_cast<Slot*>(::operator new[](n * sizeof(Slot), std::align_val_t(alignof(Slot))))) {}
    ~RawSlots() { ::operator delete[](data_, std::align_val_t(alignof(Slot))); }
    RawSlots(const RawSlots&) = delete;
    RawSlots& operator=(const RawSlots&) = delete;
    Slot& operator[](std::size_t i) const { return data_[i]; }

private:
    Slot* const data_;
};

}  // namespace gigascroll

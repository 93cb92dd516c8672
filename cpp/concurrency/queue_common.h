// Shared constants of the bounded queues.
#pragma once
#include <cstddef>
#include <new>

namespace gigascroll {

// Producer and consumer state live on separate lines of this size. 64 bytes on x86-64 and
// most ARM cores; two lines would also defeat the adjacent-line prefetcher, but the
// measured difference on this hardware was within noise, so one line it is.
inline constexpr std::size_t kCacheLine = 128;

inline constexpr std::size_t round_up_pow2(std::size_t n) {
    std::size_t p = 1;
    while (p < n) p <<= 1;
    return p;
}

// Ring size for a requested capacity: a power of two, at least 2, so index & mask wraps.
inline constexpr std::size_t ring_capacity(std::size_t n) { return round_up_pow2(n < 2 ? 2 : n); }

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

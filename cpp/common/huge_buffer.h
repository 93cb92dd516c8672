// A zeroed byte buffer for large data read at scattered places (the physical texture):
// aligned to 2 MB and advised for transparent huge pages, so that reads spread over tens of
// megabytes miss the TLB less. Where the kernel offers no huge pages it is a plain buffer.
// At least kSlack bytes past size() are readable (zero), for loads wider than the last item.
#pragma once
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>

namespace gigascroll {

class HugeBuffer {
public:
    static constexpr std::size_t kHugePage = std::size_t(2) << 20;
    static constexpr std::size_t kSlack = 64;

    HugeBuffer() = default;
    explicit HugeBuffer(std::size_t size) : size_(size) {
        if (size == 0) return;
        const std::size_t rounded = (size + kSlack + kHugePage - 1) / kHugePage * kHugePage;
        void* p = std::aligned_alloc(kHugePage, rounded);
        if (!p) throw std::bad_alloc();
        // Advice only: failure (no THP support) leaves ordinary pages.
        (void)madvise(p, rounded, MADV_HUGEPAGE);
        std::memset(p, 0, rounded);
        data_.reset(static_cast<std::uint8_t*>(p));
    }

    std::uint8_t* data() { return data_.get(); }
    const std::uint8_t* data() const { return data_.get(); }
    std::size_t size() const { return size_; }

private:
    struct Free {
        void operator()(std::uint8_t* p) const { std::free(p); }
    };
    std::unique_ptr<std::uint8_t[], Free> data_;
    std::size_t size_ = 0;
};

}  // namespace gigascroll

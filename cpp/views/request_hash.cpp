#include "views/request_hash.h"

#include "common/error.h"

namespace gigascroll {

namespace {
// VT-mobile-VR's collision rule: the finer level wins; equal levels keep the smaller key so the
// result does not depend on insertion order.
bool wins(std::uint64_t key, std::uint64_t held) {
    const std::uint32_t lk = request_level(key), lh = request_level(held);
    return lk < lh || (lk == lh && key < held);
}
}  // namespace

HashProcessor::HashProcessor(unsigned table_bits, unsigned threads)
    : shift_(64 - table_bits), threads_(threads) {
    require(table_bits >= 4 && table_bits <= 28, "hash table_bits must be in [4, 28]");
    const std::size_t size = std::size_t(1) << table_bits;
    slots_ = std::vector<std::atomic<std::uint64_t>>(size);
    for (auto& s : slots_) s.store(kNoRequest, std::memory_order_relaxed);
    used_.resize(size);
}

std::uint64_t HashProcessor::slot(std::uint64_t key, std::uint64_t salt) const {
    return (kLecuyerA64 * (key * salt)) >> shift_;
}

void HashProcessor::clear_used() {
    const std::uint32_t n = used_count_.load(std::memory_order_relaxed);
    for (std::uint32_t i = 0; i < n; ++i) slots_[used_[i]].store(kNoRequest, std::memory_order_relaxed);
    used_count_.store(0, std::memory_order_relaxed);
}

RequestSets HashProcessor::process(std::span<const FeedbackBuffer> buffers,
                                   const ResidencyLookup& lookup, std::uint64_t frame) {
    const std::scoped_lock lock(mutex_);
    const std::uint64_t salt = frame_salt(frame);
    for_each_request(buffers, threads_, [&](std::uint64_t key) {
        const std::uint64_t s = slot(key, salt);
        std::atomic<std::uint64_t>& cell = slots_[s];
        std::uint64_t held = cell.load(std::memory_order_relaxed);
        while (held != key && (held == kNoRequest || wins(key, held))) {
            if (cell.compare_exchange_weak(held, key, std::memory_order_relaxed)) {
                if (held == kNoRequest)
                    used_[used_count_.fetch_add(1, std::memory_order_relaxed)] =
                        static_cast<std::uint32_t>(s);
                break;
            }
        }
    });

    RequestSets sets;
    const std::uint32_t n = used_count_.load(std::memory_order_relaxed);
    sets.requests.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i)
        sets.requests.push_back(slots_[used_[i]].load(std::memory_order_relaxed));
    clear_used();
    resolve_requests(sets, lookup);  // validates keys: bad input throws here, table is clean
    return sets;
}

}  // namespace gigascroll

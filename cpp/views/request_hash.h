// VT-mobile-VR's result table: requests are inserted in parallel into a table of fixed size,
// slot h = a (B F) mod m (eq. 1) with B the request key (pack/tile_key.h, 64-bit eq. 2) and F the
// frame salt; on a collision the request with the smaller mip level is kept (ties: the
// smaller key), the other is lost for this frame. Its cost does not depend on how many tiles
// the paintings have, unlike the flag array.
//
// Eq. 1 with L'Ecuyer's (1999, Math. Comp. 68(225)) constants for m = 2^64:
// a = 2862933555777941757; the table has 2^k slots and the slot is the top k bits of h (the
// low bits of an LCG mod 2^64 are weak). A prime m would not do: a and F are invertible
// mod m, so two keys collide in frame F iff B1 = B2 (mod m), the same pairs in every frame,
// and the salt does nothing (the hash test shows it). With
// m = 2^64 and the top bits, h_F = F h_1 (mod 2^64): consecutive frames only repeat a
// collision if a (B1 - B2) mod 2^64 is within ~2 slot widths of 0, and F only scrambles
// well once F is large against the table size, so the salt is F = frame + kFrameOffset.
#pragma once
#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "views/request_processing.h"

namespace gigascroll {

inline constexpr std::uint64_t kLecuyerA64 = 2862933555777941757ull;  // m = 2^64
inline constexpr std::uint64_t kFrameOffset = (1ull << 20) + 1;

class HashProcessor {
public:
    // table_bits: log2 of the slot count.
    explicit HashProcessor(unsigned table_bits = 16, unsigned threads = 0);
    HashProcessor(const HashProcessor&) = delete;
    HashProcessor& operator=(const HashProcessor&) = delete;

    // The salt F of a frame number.
    static std::uint64_t frame_salt(std::uint64_t frame) { return frame + kFrameOffset; }
    // Slot of key B in the frame with salt F.
    std::uint64_t slot(std::uint64_t key, std::uint64_t salt) const;
    std::uint64_t table_size() const { return slots_.size(); }

    // Requests lost to collisions do not appear in the result (measure them against
    // BasicProcessor). Throws InvalidArgument (leaving the table empty) on a bad key.
    RequestSets process(std::span<const FeedbackBuffer> buffers, const ResidencyLookup& lookup,
                        std::uint64_t frame);

private:
    void clear_used();

    unsigned shift_;
    unsigned threads_;
    // Held by process(): the table is one frame's, so calls from several threads take turns.
    std::mutex mutex_;
    // Slots hold a request key or kNoRequest. Insertion is a CAS loop keeping the minimum
    // (level, key); relaxed order suffices because the table is only read after the
    // inserting threads joined. A slot leaves kNoRequest at most once per frame; the thread
    // whose CAS did it owns one entry of used_, claimed with a relaxed fetch_add.
    std::vector<std::atomic<std::uint64_t>> slots_;
    std::vector<std::uint32_t> used_;
    std::atomic<std::uint32_t> used_count_{0};
};

}  // namespace gigascroll

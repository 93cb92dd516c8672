// The physical cache and its page table (VT-mobile-VR §4.3): a texture of slots_x x slots_y tile
// slots, LRU replacement, and every tile of a painting's tail levels (see page_table.h),
// including its single coarsest tile, pinned so every lookup resolves. Sampling through it
// is sampling/sampler.h.
//
// Thread safety: lookup(), the read-only queries and read_lock() holders share the cache
// and may run concurrently; insert() and request() take it exclusively.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

#include "common/huge_buffer.h"
#include "loading/tile_loader.h"
#include "cache/page_table.h"
#include "pack/geometry.h"
#include "pack/texel_format.h"

namespace gigascroll {

struct CacheStats {
    std::uint64_t resident = 0, pinned = 0, slots = 0;
    std::uint64_t insertions = 0, evictions = 0, hits = 0, misses = 0;
};

class VirtualTexture {
public:
    // Reads one tile in the slots' format (slot_bytes()) for pinning at construction.
    using TileSource = std::function<void(const TileKey&, std::uint8_t*)>;

    // Largest physical texture: 16 GiB of tile slots.
    static constexpr std::size_t kMaxCacheBytes = std::size_t(16) << 30;
    // InvalidArgument if the slots cannot hold the pinned tiles plus one free slot, or their
    // texels would take more than kMaxCacheBytes. Slots hold RGB8 texels or BC1 blocks (a bc1
    // pack's tiles as stored: 6x the slots per byte).
    VirtualTexture(const PackGeometry& layout, std::uint32_t slots_x, std::uint32_t slots_y,
                   const TileSource& pinned_source, TexelFormat format = TexelFormat::Rgb8);
    // The cache of a pack, pinned tiles read from it in its slot format; remembers the pack's fingerprint so
    // that tiles of another pack (a loader opened on it) are refused.
    VirtualTexture(const TilePack& pack, std::uint32_t slots_x, std::uint32_t slots_y);

    // pack_fingerprint() of the pack the cache was built from; 0 when built from a layout.
    std::uint64_t pack_fingerprint() const { return pack_fingerprint_; }

    const PackGeometry& layout() const { return table_.layout(); }
    std::uint32_t slots_x() const { return slots_x_; }
    std::uint32_t slots_y() const { return slots_y_; }
    TexelFormat format() const { return format_; }
    std::size_t slot_bytes() const { return slot_bytes_; }

    // Copies the tile (slot_bytes() in the slots' format) into a slot (the least recently used one when full) and updates the
    // page table. A resident tile is only marked used. Returns the evicted tile, if any.
    std::optional<TileKey> insert(const TileKey& key, const std::uint8_t* data);
    // A frame's requests: resident ones count as hits and become most recently used, the
    // others count as misses and are returned (in request order, duplicates kept once).
    std::vector<TileKey> request(const std::vector<TileKey>& keys);
    bool is_resident(const TileKey& key) const;
    bool is_pinned(const TileKey& key) const;
    std::vector<TileKey> resident_tiles() const;
    CacheStats stats() const;

    // O(1) page-table read: finest resident tile covering the key (level and slot).
    PageEntry lookup(const TileKey& key) const;
    // Without the lock, for callers that already hold no concurrent updates (views' workers).
    const PageTable& page_table() const { return table_; }
    bool page_table_matches_rebuild() const;

    // Shared access for readers of the physical texture and page table (the sampler takes
    // it the way OpenImageIO's TextureSystem reads its ImageCache); insert() and request()
    // wait for it.
    std::shared_lock<std::shared_mutex> read_lock() const { return std::shared_lock(mutex_); }

    // The physical texture, tile-major: slot s holds its T x T x RGB8 texels (or its (T/4)^2
    // BC1 blocks) contiguously at s * slot_bytes(), so a bilinear footprint's two rows are T * 3 bytes apart and one
    // tile spans 14 pages rather than T (the sampler's reads are scattered over the cache).
    const std::uint8_t* physical() const { return texels_.data(); }

private:
    void check_key(const TileKey& key) const;
    std::uint32_t resident_slot(const TileKey& key) const;  // PageEntry::kNone if absent
    void store(std::uint32_t slot, const TileKey& key, const std::uint8_t* data);
    void lru_unlink(std::uint32_t s);
    void lru_push_front(std::uint32_t s);

    PageTable table_;
    std::uint32_t slots_x_, slots_y_;
    std::uint64_t pack_fingerprint_ = 0;
    TexelFormat format_;
    std::size_t slot_bytes_;
    HugeBuffer texels_;
    std::unordered_map<std::uint64_t, std::uint32_t> slot_of_;  // packed key -> slot
    std::vector<std::uint64_t> key_of_;                        // slot -> packed key
    std::vector<std::uint8_t> pinned_;
    std::vector<std::uint32_t> free_;
    // LRU list over unpinned resident slots: head = most recently used.
    static constexpr std::uint32_t kNil = 0xFFFFFFFFu;
    std::vector<std::uint32_t> prev_, next_;
    std::uint32_t head_ = kNil, tail_ = kNil;
    CacheStats stats_;
    mutable std::shared_mutex mutex_;
};

}  // namespace gigascroll

// The mip-mapped page table (VT-mobile-VR §4.3, Mayer-VT §3.3). Entry (painting p, level l,
// tile x, y) names the finest resident tile covering that tile: its level and physical slot.
// When the exact tile is missing the entry is a fallback to a resident ancestor, so the
// sampler's "try LOD, LOD+1, ..." (Vulkan-SVT) is one read.
//
// Storage follows the pack's merged layout: level l of the merged table is (Mc >> l) x
// (Nc >> l) entries and painting p owns the (Mp >> l) x (Np >> l) block at (off >> l), for
// l < merged_levels(p). Coarser "tail" levels, where that block would be thinner than one
// entry, live in a small table per painting sized to the real tile grid. Every tile of a
// tail level and of the coarsest level is pinned by the cache, so every lookup resolves.
//
// Updates are incremental: inserting a tile rewrites the entries it covers that pointed to
// something coarser; evicting one rewrites the entries that pointed to it with its parent's
// entry. rebuild() recomputes every entry from the resident set by walking ancestors: the
// reference the tests compare the incremental state against.
//
// Thread safety: lookup() is const and may run on any number of threads while no update runs.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "pack/geometry.h"
#include "pack/tile_key.h"

namespace gigascroll {

struct PageEntry {
    static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
    std::uint32_t bits = kNone;  // level << 24 | slot
    static PageEntry make(std::uint32_t level, std::uint32_t slot) { return {(level << 24) | slot}; }
    bool valid() const { return bits != kNone; }
    std::uint32_t level() const { return bits >> 24; }
    std::uint32_t slot() const { return bits & 0xFFFFFFu; }
    friend bool operator==(PageEntry, PageEntry) = default;
};

class PageTable {
public:
    explicit PageTable(const PackGeometry& layout);
    // Not copyable: views_ point into the table's own storage.
    PageTable(const PageTable&) = delete;
    PageTable& operator=(const PageTable&) = delete;

    // O(1): the finest resident tile covering (p, l, tx, ty) (tx, ty in that level's tile
    // grid, padding included: tx < Mp >> l for merged levels, < tiles_x(l) for tail levels).
    PageEntry lookup(std::uint32_t p, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) const {
        return cref(p, l, tx, ty);
    }
    // Extent of level l's entry grid for painting p.
    std::uint32_t grid_w(std::uint32_t p, std::uint32_t l) const;
    std::uint32_t grid_h(std::uint32_t p, std::uint32_t l) const;

    void insert(const TileKey& key, std::uint32_t slot);
    void evict(const TileKey& key);
    // Recomputes every entry from scratch; resident(key) -> slot or PageEntry::kNone.
    void rebuild(const std::function<std::uint32_t(const TileKey&)>& resident);
    // Same computation into a copy, for comparing against the incremental state.
    bool equals_rebuild(const std::function<std::uint32_t(const TileKey&)>& resident) const;

    const PackGeometry& layout() const { return layout_; }
    std::size_t entry_count() const;

private:
    PageEntry& ref(std::uint32_t p, std::uint32_t l, std::uint32_t x, std::uint32_t y) {
        return const_cast<PageEntry&>(cref(p, l, x, y));
    }
    const PageEntry& cref(std::uint32_t p, std::uint32_t l, std::uint32_t x, std::uint32_t y) const {
        const LevelView& v = views_[p][l];
        return v.base[std::size_t(y) * v.stride + x];
    }
    // Calls f(entry) for every entry of levels <= key.level under key's tile.
    template <typename F>
    void for_each_covered(const TileKey& key, F&& f);

    // Where level l of painting p starts (its region's first entry) and its row stride: the
    // merged table at offset >> l with stride Mc >> l, or the painting's tail table. Precomputed
    // so a lookup is one multiply-add, the sampler's hot path.
    struct LevelView {
        PageEntry* base;
        std::size_t stride;
    };

    PackGeometry layout_;
    std::vector<std::vector<LevelView>> views_;            // [painting][level]
    std::vector<std::vector<PageEntry>> merged_;            // [level][row-major Mc>>l x Nc>>l]
    std::vector<std::vector<std::vector<PageEntry>>> tail_;  // [painting][level - merged][...]
};

}  // namespace gigascroll

#include "cache/virtual_texture.h"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <string>
#include <unordered_set>

#include "common/error.h"
#include "common/limits.h"
#include "pack/reader.h"

namespace gigascroll {

VirtualTexture::VirtualTexture(const PackGeometry& layout, std::uint32_t slots_x,
                               std::uint32_t slots_y, const TileSource& pinned_source,
                               TexelFormat format)
    : table_(layout), slots_x_(slots_x), slots_y_(slots_y), format_(format),
      slot_bytes_(texel_format_tile_bytes(format, layout.tile_size)) {
    require(format != TexelFormat::Bc1 ||
                (layout.tile_size % 4 == 0 && layout.payload() % 4 == 0),
            "bc1 slots need tile_size and payload that are multiples of 4");
    require(slots_x >= 1 && slots_y >= 1 && std::uint64_t(slots_x) * slots_y < (1u << 24),
            "slots must be positive and fewer than 2^24 in total");
    const std::uint32_t n = slots_x * slots_y;
    // Checked before the pinned tiles are listed or anything is allocated.
    require_memory(double(n), double(slot_bytes_), double(kMaxCacheBytes),
                   "slots=(" + std::to_string(slots_x) + ", " + std::to_string(slots_y) + ")");
    // Pinned: every tile of the tail levels (which include the coarsest, single-tile level).
    std::vector<TileKey> pinned;
    for (std::uint32_t p = 0; p < layout.paintings.size(); ++p) {
        const PaintingGeometry& pt = layout.paintings[p];
        const std::uint32_t first = std::min(pt.merged_levels(), pt.levels() - 1);
        for (std::uint32_t l = first; l < pt.levels(); ++l)
            for (std::uint32_t y = 0; y < pt.tiles_y(l); ++y)
                for (std::uint32_t x = 0; x < pt.tiles_x(l); ++x) pinned.push_back({p, l, x, y});
    }
    require(pinned.size() < n, "slots=(" + std::to_string(slots_x) + ", " + std::to_string(slots_y) +
                                   ") cannot hold the " + std::to_string(pinned.size()) +
                                   " pinned coarse tiles plus one streamed tile");
    texels_ = HugeBuffer(std::size_t(n) * slot_bytes_);
    key_of_.assign(n, 0);
    pinned_.assign(n, 0);
    prev_.assign(n, kNil);
    next_.assign(n, kNil);
    stats_.slots = n;
    std::vector<std::uint8_t> tile(slot_bytes_);
    std::uint32_t slot = 0;
    for (const TileKey& k : pinned) {
        pinned_source(k, tile.data());
        pinned_[slot] = 1;
        store(slot, k, tile.data());
        ++slot;
    }
    stats_.pinned = pinned.size();
    for (std::uint32_t s = n; s-- > slot;) free_.push_back(s);  // hand out low slots first
}

VirtualTexture::VirtualTexture(const TilePack& pack, std::uint32_t slots_x, std::uint32_t slots_y)
    : VirtualTexture(pack.geometry(), slots_x, slots_y, [&](const TileKey& k, std::uint8_t* out) {
          pack.read_slot_tile(k.painting, k.level, k.tx, k.ty, out);
      }, pack.slot_format()) {
    pack_fingerprint_ = gigascroll::pack_fingerprint(pack);
}

void VirtualTexture::check_key(const TileKey& k) const {
    const auto& ps = layout().paintings;
    require(k.painting < ps.size(), "painting " + std::to_string(k.painting) + " out of range");
    const PaintingGeometry& p = ps[k.painting];
    require(k.level < p.levels(), "level " + std::to_string(k.level) + " out of range");
    require(k.tx < p.tiles_x(k.level) && k.ty < p.tiles_y(k.level),
            "tile (" + std::to_string(k.tx) + ", " + std::to_string(k.ty) + ") out of range at level " +
                std::to_string(k.level));
}

std::uint32_t VirtualTexture::resident_slot(const TileKey& key) const {
    auto it = slot_of_.find(key.packed());
    return it == slot_of_.end() ? PageEntry::kNone : it->second;
}

void VirtualTexture::store(std::uint32_t slot, const TileKey& key, const std::uint8_t* data) {
    std::memcpy(texels_.data() + std::size_t(slot) * slot_bytes_, data, slot_bytes_);
    key_of_[slot] = key.packed();
    slot_of_[key.packed()] = slot;
    table_.insert(key, slot);
    ++stats_.insertions;
}

void VirtualTexture::lru_unlink(std::uint32_t s) {
    (prev_[s] == kNil ? head_ : next_[prev_[s]]) = next_[s];
    (next_[s] == kNil ? tail_ : prev_[next_[s]]) = prev_[s];
    prev_[s] = next_[s] = kNil;
}

void VirtualTexture::lru_push_front(std::uint32_t s) {
    prev_[s] = kNil;
    next_[s] = head_;
    (head_ == kNil ? tail_ : prev_[head_]) = s;
    head_ = s;
}

std::optional<TileKey> VirtualTexture::insert(const TileKey& key, const std::uint8_t* data) {
    check_key(key);
    std::unique_lock lock(mutex_);
    if (const std::uint32_t s = resident_slot(key); s != PageEntry::kNone) {
        if (!pinned_[s]) {
            lru_unlink(s);
            lru_push_front(s);
        }
        return std::nullopt;
    }
    std::optional<TileKey> evicted;
    std::uint32_t s;
    if (!free_.empty()) {
        s = free_.back();
        free_.pop_back();
    } else {
        s = tail_;  // least recently used
        lru_unlink(s);
        evicted = TileKey::unpack(key_of_[s]);
        slot_of_.erase(key_of_[s]);
        table_.evict(*evicted);
        ++stats_.evictions;
    }
    store(s, key, data);
    lru_push_front(s);
    return evicted;
}

std::vector<TileKey> VirtualTexture::request(const std::vector<TileKey>& keys) {
    for (const TileKey& k : keys) check_key(k);
    std::unique_lock lock(mutex_);
    std::vector<TileKey> missing;
    std::unordered_set<std::uint64_t> seen;
    for (const TileKey& k : keys) {
        const std::uint32_t s = resident_slot(k);
        if (s != PageEntry::kNone) {
            ++stats_.hits;
            if (!pinned_[s]) {
                lru_unlink(s);
                lru_push_front(s);
            }
        } else {
            ++stats_.misses;
            if (seen.insert(k.packed()).second) missing.push_back(k);
        }
    }
    return missing;
}

bool VirtualTexture::is_resident(const TileKey& key) const {
    check_key(key);
    std::shared_lock lock(mutex_);
    return resident_slot(key) != PageEntry::kNone;
}

bool VirtualTexture::is_pinned(const TileKey& key) const {
    check_key(key);
    std::shared_lock lock(mutex_);
    const std::uint32_t s = resident_slot(key);
    return s != PageEntry::kNone && pinned_[s];
}

std::vector<TileKey> VirtualTexture::resident_tiles() const {
    std::shared_lock lock(mutex_);
    std::vector<TileKey> out;
    for (const auto& [k, s] : slot_of_) out.push_back(TileKey::unpack(k));
    std::sort(out.begin(), out.end(), [](const TileKey& a, const TileKey& b) { return a.packed() < b.packed(); });
    return out;
}

CacheStats VirtualTexture::stats() const {
    std::shared_lock lock(mutex_);
    CacheStats s = stats_;
    s.resident = slot_of_.size();
    return s;
}

PageEntry VirtualTexture::lookup(const TileKey& key) const {
    const auto& ps = layout().paintings;
    require(key.painting < ps.size() && key.level < ps[key.painting].levels() &&
                key.tx < table_.grid_w(key.painting, key.level) &&
                key.ty < table_.grid_h(key.painting, key.level),
            "page-table key out of range");
    std::shared_lock lock(mutex_);
    return table_.lookup(key.painting, key.level, key.tx, key.ty);
}

bool VirtualTexture::page_table_matches_rebuild() const {
    std::shared_lock lock(mutex_);
    return table_.equals_rebuild([&](const TileKey& k) { return resident_slot(k); });
}

}  // namespace gigascroll

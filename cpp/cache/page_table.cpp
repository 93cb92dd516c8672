#include "cache/page_table.h"

#include <algorithm>

#include "common/error.h"

namespace gigascroll {

PageTable::PageTable(const PackGeometry& layout) : layout_(layout) {
    layout_.validate();
    std::uint32_t merged_levels = 0;
    for (const auto& p : layout_.paintings) merged_levels = std::max(merged_levels, p.merged_levels());
    merged_.resize(merged_levels);
    for (std::uint32_t l = 0; l < merged_levels; ++l)
        merged_[l].assign(std::size_t(layout_.table_width >> l) * (layout_.table_height >> l), PageEntry{});
    tail_.resize(layout_.paintings.size());
    for (std::size_t i = 0; i < layout_.paintings.size(); ++i) {
        const PaintingGeometry& p = layout_.paintings[i];
        for (std::uint32_t l = p.merged_levels(); l < p.levels(); ++l)
            tail_[i].emplace_back(std::size_t(p.tiles_x(l)) * p.tiles_y(l), PageEntry{});
    }
    views_.resize(layout_.paintings.size());
    for (std::size_t i = 0; i < layout_.paintings.size(); ++i) {
        const PaintingGeometry& p = layout_.paintings[i];
        for (std::uint32_t l = 0; l < p.levels(); ++l) {
            if (l < p.merged_levels()) {
                const std::size_t stride = layout_.table_width >> l;
                views_[i].push_back({merged_[l].data() + std::size_t(p.table_y() >> l) * stride + (p.table_x() >> l),
                                     stride});
            } else {
                views_[i].push_back({tail_[i][l - p.merged_levels()].data(), p.tiles_x(l)});
            }
        }
    }
}

std::uint32_t PageTable::grid_w(std::uint32_t p, std::uint32_t l) const {
    const PaintingGeometry& pt = layout_.paintings[p];
    return l < pt.merged_levels() ? pt.page_table_width() >> l : pt.tiles_x(l);
}

std::uint32_t PageTable::grid_h(std::uint32_t p, std::uint32_t l) const {
    const PaintingGeometry& pt = layout_.paintings[p];
    return l < pt.merged_levels() ? pt.page_table_height() >> l : pt.tiles_y(l);
}

std::size_t PageTable::entry_count() const {
    std::size_t n = 0;
    for (const auto& m : merged_) n += m.size();
    for (const auto& t : tail_)
        for (const auto& l : t) n += l.size();
    return n;
}

template <typename F>
void PageTable::for_each_covered(const TileKey& key, F&& f) {
    for (std::uint32_t k = key.level + 1; k-- > 0;) {
        const std::uint32_t s = key.level - k;
        const std::uint32_t x0 = key.tx << s, y0 = key.ty << s;
        const std::uint32_t x1 = std::min((key.tx + 1) << s, grid_w(key.painting, k));
        const std::uint32_t y1 = std::min((key.ty + 1) << s, grid_h(key.painting, k));
        for (std::uint32_t y = y0; y < y1; ++y)
            for (std::uint32_t x = x0; x < x1; ++x) f(ref(key.painting, k, x, y));
    }
}

void PageTable::insert(const TileKey& key, std::uint32_t slot) {
    require(key.painting < layout_.paintings.size() &&
                key.level < layout_.paintings[key.painting].levels() &&
                key.tx < layout_.paintings[key.painting].tiles_x(key.level) &&
                key.ty < layout_.paintings[key.painting].tiles_y(key.level),
            "page table: tile key out of range");
    const PageEntry e = PageEntry::make(key.level, slot);
    // Entries pointing at a finer tile keep it; coarser or missing ones now point here.
    for_each_covered(key, [&](PageEntry& x) {
        if (!x.valid() || x.level() >= key.level) x = e;
    });
}

void PageTable::evict(const TileKey& key) {
    const PaintingGeometry& pt = layout_.paintings[key.painting];
    // The parent's entry is the finest resident tile strictly coarser than this one.
    const PageEntry parent = key.level + 1 < pt.levels()
                                 ? lookup(key.painting, key.level + 1, key.tx >> 1, key.ty >> 1)
                                 : PageEntry{};
    for_each_covered(key, [&](PageEntry& x) {
        if (x.valid() && x.level() == key.level) x = parent;
    });
}

void PageTable::rebuild(const std::function<std::uint32_t(const TileKey&)>& resident) {
    for (std::uint32_t p = 0; p < layout_.paintings.size(); ++p) {
        const PaintingGeometry& pt = layout_.paintings[p];
        for (std::uint32_t l = 0; l < pt.levels(); ++l) {
            for (std::uint32_t y = 0; y < grid_h(p, l); ++y)
                for (std::uint32_t x = 0; x < grid_w(p, l); ++x) {
                    // Walk up the ancestors until a resident real tile answers.
                    PageEntry e;
                    for (std::uint32_t a = l; a < pt.levels(); ++a) {
                        const std::uint32_t ax = x >> (a - l), ay = y >> (a - l);
                        if (ax >= pt.tiles_x(a) || ay >= pt.tiles_y(a)) continue;
                        const std::uint32_t slot = resident(TileKey{p, a, ax, ay});
                        if (slot != PageEntry::kNone) {
                            e = PageEntry::make(a, slot);
                            break;
                        }
                    }
                    ref(p, l, x, y) = e;
                }
        }
    }
}

bool PageTable::equals_rebuild(const std::function<std::uint32_t(const TileKey&)>& resident) const {
    PageTable fresh(layout_);
    fresh.rebuild(resident);
    return fresh.merged_ == merged_ && fresh.tail_ == tail_;
}

}  // namespace gigascroll

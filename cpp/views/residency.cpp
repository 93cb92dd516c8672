#include "views/residency.h"

#include <algorithm>
#include <sstream>

#include "common/error.h"

namespace gigascroll {

PaintingSet::PaintingSet(std::vector<PaintingGeometry> paintings) : paintings_(std::move(paintings)) {
    require(!paintings_.empty(), "need at least one painting");
    require(paintings_.size() < kMaxPaintings, "too many paintings");
    for (const PaintingGeometry& p : paintings_)
        require(p.fits_request_key(), "painting too large: more than 65536 tiles per axis");
}

bool PaintingSet::valid(std::uint64_t key) const {
    const TileKey r = unpack_request(key);
    if (r.painting >= paintings_.size()) return false;
    const PaintingGeometry& p = paintings_[r.painting];
    return r.level < p.levels() && r.tx < p.tiles_x(r.level) && r.ty < p.tiles_y(r.level);
}

void PaintingSet::validate(std::uint64_t key) const {
    if (valid(key)) return;
    const TileKey r = unpack_request(key);
    std::ostringstream s;
    s << "request key 0x" << std::hex << key << std::dec << " (painting " << r.painting
      << ", level " << r.level << ", tile " << r.tx << ", " << r.ty
      << ") names no tile of the " << paintings_.size() << " known paintings";
    throw InvalidArgument(s.str());
}

ResidentSet::ResidentSet(std::vector<PaintingGeometry> paintings)
    : PaintingSet(std::move(paintings)) {}

void ResidentSet::insert(std::uint64_t key) {
    validate(key);
    keys_.insert(key);
}
void ResidentSet::erase(std::uint64_t key) { keys_.erase(key); }

bool ResidentSet::contains(std::uint64_t key) const {
    if (!valid(key)) return false;
    const TileKey r = unpack_request(key);
    return r.level + 1 == paintings()[r.painting].levels() || keys_.count(key) != 0;
}

std::uint32_t ResidentSet::resident_level(std::uint64_t request) const {
    validate(request);
    const TileKey r = unpack_request(request);
    const std::uint32_t top = paintings()[r.painting].levels() - 1;
    for (std::uint32_t l = r.level; l < top; ++l)
        if (keys_.count(ancestor_request(request, l))) return l;
    return top;
}

TileIndex::TileIndex(std::vector<PaintingGeometry> paintings) : PaintingSet(std::move(paintings)) {
    base_.push_back(0);
    for (const auto& p : this->paintings()) base_.push_back(base_.back() + p.total_tiles());
}

std::uint64_t TileIndex::index(std::uint64_t key) const {
    validate(key);
    const TileKey r = unpack_request(key);
    const PaintingGeometry& p = paintings()[r.painting];
    return base_[r.painting] + p.level_offset(r.level) + std::uint64_t(r.ty) * p.tiles_x(r.level) +
           r.tx;
}

std::uint64_t TileIndex::key(std::uint64_t index) const {
    require(index < size(), "tile index out of range");
    const auto pi = static_cast<std::uint32_t>(
        std::upper_bound(base_.begin(), base_.end(), index) - base_.begin() - 1);
    const PaintingGeometry& p = paintings()[pi];
    std::uint64_t rest = index - base_[pi];
    std::uint32_t level = 0;
    while (p.level_offset(level + 1) <= rest) ++level;
    rest -= p.level_offset(level);
    return pack_request(pi, level, static_cast<std::uint32_t>(rest % p.tiles_x(level)),
                        static_cast<std::uint32_t>(rest / p.tiles_x(level)));
}

}  // namespace gigascroll

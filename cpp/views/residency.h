// What request processing asks the page table: the finest resident tile covering a request.
// The runtime's page table implements ResidencyLookup; ResidentSet is a plain reference
// implementation for tests and benchmarks.
#pragma once
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "pack/tile_key.h"
#include "pack/geometry.h"

namespace gigascroll {

class ResidencyLookup {
public:
    virtual ~ResidencyLookup() = default;
    // The level (>= the request's level) of the finest resident tile covering `request`.
    // Must be safe to call from several threads at once while nobody modifies it.
    virtual std::uint32_t resident_level(std::uint64_t request) const = 0;
};

// The response to a request: the resident ancestor (or the request itself).
inline std::uint64_t response_of(const ResidencyLookup& lookup, std::uint64_t request) {
    return ancestor_request(request, lookup.resident_level(request));
}

// Paintings indexed by id p; validates request keys against their tile grids.
class PaintingSet {
public:
    explicit PaintingSet(std::vector<PaintingGeometry> paintings);
    const std::vector<PaintingGeometry>& paintings() const { return paintings_; }
    // Throws InvalidArgument unless `key` names an existing tile.
    void validate(std::uint64_t key) const;
    bool valid(std::uint64_t key) const;

private:
    std::vector<PaintingGeometry> paintings_;
};

// A set of resident tiles; the coarsest tile of every painting is always resident (VT-mobile-VR).
class ResidentSet : public ResidencyLookup, public PaintingSet {
public:
    explicit ResidentSet(std::vector<PaintingGeometry> paintings);
    void insert(std::uint64_t key);
    void erase(std::uint64_t key);
    bool contains(std::uint64_t key) const;
    std::size_t size() const { return keys_.size(); }
    std::uint32_t resident_level(std::uint64_t request) const override;

private:
    std::unordered_set<std::uint64_t> keys_;
};

// Flat tile numbering over several paintings (Vulkan-SVT's page index, painting after painting):
// index = first index of painting p + tiles of levels 0..l-1 + y * tiles_x(l) + x.
class TileIndex : public PaintingSet {
public:
    explicit TileIndex(std::vector<PaintingGeometry> paintings);
    std::uint64_t size() const { return base_.back(); }
    // Throws InvalidArgument for a key outside every painting.
    std::uint64_t index(std::uint64_t key) const;
    std::uint64_t key(std::uint64_t index) const;

private:
    std::vector<std::uint64_t> base_;  // paintings + 1 entries
};

}  // namespace gigascroll

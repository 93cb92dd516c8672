// Which tiles to load this frame, from the frame's load-command set (VT-mobile-VR §4.2.2).
//   DirectLoading (VT-mobile-VR): load the missing requested tiles themselves, at most N per
//     frame; the rest are issued on the following frames until a new command set replaces
//     them.
//   MipByMipLoading (van Waveren): for each miss load the coarsest missing ancestor first,
//     so a tile sharpens one level per load round trip.
// Both skip tiles already in flight (issued, not yet loaded); the frame loop reports loaded
// tiles with loaded().
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <unordered_set>
#include <vector>

#include "views/residency.h"

namespace gigascroll {

class InFlight {
public:
    bool contains(std::uint64_t key) const { return keys_.count(key) != 0; }
    void add(std::uint64_t key) { keys_.insert(key); }
    void loaded(std::span<const std::uint64_t> keys) {
        for (auto k : keys) keys_.erase(k);
    }
    std::size_t size() const { return keys_.size(); }

private:
    std::unordered_set<std::uint64_t> keys_;
};

class DirectLoading {
public:
    explicit DirectLoading(std::size_t per_frame = 16);
    // A new command set replaces what is left of the previous one (order = priority).
    void set_commands(std::span<const std::uint64_t> commands);
    // Up to per_frame commands that are neither resident now nor in flight.
    std::vector<std::uint64_t> issue(const ResidencyLookup& lookup);
    void loaded(std::span<const std::uint64_t> keys) { in_flight_.loaded(keys); }
    std::size_t backlog() const { return pending_.size(); }
    std::size_t in_flight() const { return in_flight_.size(); }

private:
    std::size_t per_frame_;
    std::deque<std::uint64_t> pending_;
    InFlight in_flight_;
};

class MipByMipLoading {
public:
    explicit MipByMipLoading(std::size_t per_frame = 16);
    // The coarsest missing ancestor of each command (level resident_level - 1), distinct,
    // coarsest first, at most per_frame, skipping tiles in flight. A new call replaces the
    // previous command set: there is no backlog, the next set asks again.
    std::vector<std::uint64_t> issue(std::span<const std::uint64_t> commands,
                                     const ResidencyLookup& lookup);
    void loaded(std::span<const std::uint64_t> keys) { in_flight_.loaded(keys); }
    std::size_t in_flight() const { return in_flight_.size(); }

private:
    std::size_t per_frame_;
    InFlight in_flight_;
};

}  // namespace gigascroll

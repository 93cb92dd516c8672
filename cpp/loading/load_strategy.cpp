#include "loading/load_strategy.h"

#include <algorithm>

#include "common/error.h"

namespace gigascroll {

DirectLoading::DirectLoading(std::size_t per_frame) : per_frame_(per_frame) {
    require(per_frame > 0, "tiles per frame (the direct-loading threshold) must be > 0");
}

void DirectLoading::set_commands(std::span<const std::uint64_t> commands) {
    pending_.assign(commands.begin(), commands.end());
}

std::vector<std::uint64_t> DirectLoading::issue(const ResidencyLookup& lookup) {
    std::vector<std::uint64_t> out;
    while (!pending_.empty() && out.size() < per_frame_) {
        const std::uint64_t key = pending_.front();
        pending_.pop_front();
        if (in_flight_.contains(key) || lookup.resident_level(key) == request_level(key)) continue;
        in_flight_.add(key);
        out.push_back(key);
    }
    return out;
}

MipByMipLoading::MipByMipLoading(std::size_t per_frame) : per_frame_(per_frame) {
    require(per_frame > 0, "tiles per frame must be > 0");
}

std::vector<std::uint64_t> MipByMipLoading::issue(std::span<const std::uint64_t> commands,
                                                  const ResidencyLookup& lookup) {
    std::vector<std::uint64_t> wanted;
    for (std::uint64_t key : commands) {
        const std::uint32_t resident = lookup.resident_level(key);
        if (resident == request_level(key)) continue;  // already answered exactly
        const std::uint64_t ancestor = ancestor_request(key, resident - 1);
        if (!in_flight_.contains(ancestor)) wanted.push_back(ancestor);
    }
    // Coarsest first; equal levels by key so the choice is deterministic.
    std::sort(wanted.begin(), wanted.end(), [](std::uint64_t a, std::uint64_t b) {
        const auto la = request_level(a), lb = request_level(b);
        return la != lb ? la > lb : a < b;
    });
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    if (wanted.size() > per_frame_) wanted.resize(per_frame_);
    for (auto k : wanted) in_flight_.add(k);
    return wanted;
}

}  // namespace gigascroll

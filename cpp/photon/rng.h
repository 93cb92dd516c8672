// Counter-based randomness: every photon, pixel sample and shading point derives its own
// stream from (seed, index), so results do not depend on the thread count or schedule.
#pragma once
#include <cstdint>

namespace gigascroll {

inline std::uint64_t mix64(std::uint64_t z) {  // splitmix64 finaliser
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

inline std::uint64_t hash_combine(std::uint64_t a, std::uint64_t b) {
    return mix64(a ^ (b + 0x9e3779b97f4a7c15ULL + (a << 6) + (a >> 2)));
}

// PCG32 (O'Neill), seeded from a 64-bit key.
class Rng {
public:
    explicit Rng(std::uint64_t key) : state_(0), inc_((mix64(key ^ 0x5851f42d4c957f2dULL) << 1) | 1u) {
        next();
        state_ += mix64(key);
        next();
    }
    std::uint32_t next() {
        const std::uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rot = static_cast<std::uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
    }
    // Uniform in [0, 1): 24 random bits so the result is never rounded up to 1.
    float uniform() { return float(next() >> 8) * 0x1p-24f; }

private:
    std::uint64_t state_, inc_;
};

}  // namespace gigascroll

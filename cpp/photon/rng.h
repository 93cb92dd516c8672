// Counter-based randomness (Philox4x32-10, Salmon et al. 2011, "Parallel random numbers: as
// easy as 1, 2, 3"). Every random number is a keyed bijection of its coordinates:
//   key     = the render's 64-bit seed,
//   counter = (index: photon number, pixel or shading-point key; stream: what the numbers are
//              for and in which pass; block: position within that stream).
// So results do not depend on the thread count or schedule, and two seeds are two keys of a
// block cipher: their streams are independent, not shifted copies of each other (deriving a
// PCG seed from hash_combine(seed, i) made seed s + 1 replay seed s's photons ~65 indices on).
#pragma once
#include <cstdint>

namespace gigascroll {

inline std::uint64_t mix64(std::uint64_t z) {  // splitmix64 finaliser
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

// Hashes b into a (for keys built from several coordinates, e.g. quantised positions).
inline std::uint64_t hash_combine(std::uint64_t a, std::uint64_t b) {
    return mix64(a ^ (b + 0x9e3779b97f4a7c15ULL + (a << 6) + (a >> 2)));
}

struct Philox4x32Block {
    std::uint32_t v[4];
};

// Philox4x32 with 10 rounds on counter c under key k (Random123's philox4x32_R(10, ...)).
inline Philox4x32Block philox4x32_10(const std::uint32_t c_in[4], const std::uint32_t k_in[2]) {
    std::uint32_t c0 = c_in[0], c1 = c_in[1], c2 = c_in[2], c3 = c_in[3];
    std::uint32_t k0 = k_in[0], k1 = k_in[1];
    for (int round = 0; round < 10; ++round) {
        if (round > 0) {  // Weyl key schedule
            k0 += 0x9E3779B9u;
            k1 += 0xBB67AE85u;
        }
        const std::uint64_t p0 = std::uint64_t(0xD2511F53u) * c0, p1 = std::uint64_t(0xCD9E8D57u) * c2;
        const auto hi0 = std::uint32_t(p0 >> 32), lo0 = std::uint32_t(p0);
        const auto hi1 = std::uint32_t(p1 >> 32), lo1 = std::uint32_t(p1);
        c0 = hi1 ^ c1 ^ k0;
        c1 = lo1;
        c2 = hi0 ^ c3 ^ k1;
        c3 = lo0;
    }
    return {{c0, c1, c2, c3}};
}

// What a stream of random numbers is for; part of the counter so uses never overlap.
enum class StreamKind : std::uint32_t { Photon = 1, Pixel = 2, Light = 3 };

// The counter's stream word: kind (4 bits), a sub-stream such as the stereo eye (4 bits) and
// the progressive pass (24 bits).
inline std::uint32_t stream_id(StreamKind kind, std::uint32_t pass = 0, std::uint32_t sub = 0) {
    return (std::uint32_t(kind) << 28) | ((sub & 0xfu) << 24) | (pass & 0xffffffu);
}
constexpr std::uint32_t kMaxPasses = 1u << 24;

// The numbers of one (seed, stream, index), four per Philox block.
class Rng {
public:
    Rng(std::uint64_t seed, std::uint32_t stream, std::uint64_t index)
        : key_{std::uint32_t(seed), std::uint32_t(seed >> 32)},
          ctr_{std::uint32_t(index), std::uint32_t(index >> 32), stream, 0} {}

    std::uint32_t next() {
        if (used_ == 4) {
            block_ = philox4x32_10(ctr_, key_);
            ++ctr_[3];
            used_ = 0;
        }
        return block_.v[used_++];
    }
    // Uniform in [0, 1): 24 random bits so the result is never rounded up to 1.
    float uniform() { return float(next() >> 8) * 0x1p-24f; }

private:
    std::uint32_t key_[2];
    std::uint32_t ctr_[4];
    Philox4x32Block block_{};
    int used_ = 4;
};

}  // namespace gigascroll

#include "pack/ink_landscape.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/error.h"
#include "common/parallel.h"

namespace gigascroll {
namespace {

// Integer hash (splitmix64 finaliser): the only source of randomness, so output is stable.
inline std::uint64_t mix(std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
inline double unit(std::uint64_t h) { return double(h >> 11) * (1.0 / 9007199254740992.0); }
// Lattice hash for 2D value noise: one multiply-xorshift round is enough for texture.
inline std::uint64_t key2(std::int64_t a, std::int64_t b, std::uint64_t s) {
    std::uint64_t h = std::uint64_t(a) * 0x8CB92BA72F3D8DD7ull ^ std::uint64_t(b) * 0xD6E8FEB86659FD93ull ^ s;
    h ^= h >> 32;
    h *= 0x9E3779B97F4A7C15ull;
    return h ^ (h >> 29);
}
inline double smooth(double t) { return t * t * (3 - 2 * t); }

double noise1(double x, std::uint64_t s) {
    const double f = std::floor(x);
    const auto i = static_cast<std::int64_t>(f);
    const double t = smooth(x - f);
    const double a = unit(mix(std::uint64_t(i) ^ s)), b = unit(mix(std::uint64_t(i + 1) ^ s));
    return a + (b - a) * t;
}

double noise2(double x, double y, std::uint64_t s) {
    const double fx = std::floor(x), fy = std::floor(y);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
    const double tx = smooth(x - fx), ty = smooth(y - fy);
    const double a = unit(key2(ix, iy, s)), b = unit(key2(ix + 1, iy, s));
    const double c = unit(key2(ix, iy + 1, s)), d = unit(key2(ix + 1, iy + 1, s));
    return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

// One octave of 2D value noise along a row (y fixed, x increasing): lattice corners are
// re-hashed only when x crosses a cell, which is rare at these frequencies.
class RowNoise {
public:
    RowNoise() : RowNoise(1, 0, 0) {}
    RowNoise(double scale_x, double y_scaled, std::uint64_t s) : scale_(scale_x), s_(s) {
        const double fy = std::floor(y_scaled);
        iy_ = static_cast<std::int64_t>(fy);
        ty_ = smooth(y_scaled - fy);
    }
    double operator()(double x) {
        x *= scale_;
        const double fx = std::floor(x);
        const auto ix = static_cast<std::int64_t>(fx);
        if (ix != ix_) {
            ix_ = ix;
            const double a = unit(key2(ix, iy_, s_)), b = unit(key2(ix + 1, iy_, s_));
            const double c = unit(key2(ix, iy_ + 1, s_)), d = unit(key2(ix + 1, iy_ + 1, s_));
            lo_ = a + (c - a) * ty_;  // column ix, blended in y
            hi_ = b + (d - b) * ty_;  // column ix + 1
        }
        return lo_ + (hi_ - lo_) * smooth(x - fx);
    }

private:
    double scale_;
    std::uint64_t s_;
    std::int64_t iy_ = 0, ix_ = INT64_MIN;
    double ty_ = 0, lo_ = 0, hi_ = 0;
};

// fbm over `Octaves` RowNoise octaves (lacunarity 2.01, gain 0.5), normalised to [0, 1].
template <int Octaves>
struct RowFbm {
    RowFbm(double sx, double sy, double v, std::uint64_t s) {
        for (int o = 0; o < Octaves; ++o) {
            const double f = std::pow(2.01, o);
            oct[o] = RowNoise(sx * f, v * sy * f, s + 7919 * o);
        }
    }
    double operator()(double u) {
        double sum = 0, amp = 0.5, norm = 0;
        for (int o = 0; o < Octaves; ++o) {
            sum += amp * oct[o](u);
            norm += amp;
            amp *= 0.5;
        }
        return sum / norm;
    }
    RowNoise oct[Octaves] = {};
};

double fbm1(double x, std::uint64_t s, int octaves) {
    double sum = 0, amp = 0.5, norm = 0;
    for (int o = 0; o < octaves; ++o) {
        sum += amp * noise1(x, s + 977 * o);
        norm += amp;
        x *= 2.03;
        amp *= 0.5;
    }
    return sum / norm;
}

constexpr int kLayers = 4;

}  // namespace

void render_ink_landscape(std::uint32_t width, std::uint32_t height, std::uint32_t y0,
                          std::uint32_t rows, std::uint64_t seed, std::uint8_t* out,
                          unsigned threads) {
    require(width > 0 && height > 0, "painting size must be positive");
    require(std::uint64_t(y0) + rows <= height, "rows outside the painting");
    const double H = height;
    // Per column and layer: ridge line (in units of the painting height, 0 = top) and
    // whether a tree stands there. Depends on x only, so computed once per band.
    std::vector<float> ridge(std::size_t(width) * kLayers);
    std::vector<float> tree(std::size_t(width) * kLayers);
    parallel_for(width, 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t x = b; x < e; ++x) {
            const double u = double(x) / H;
            for (int k = 0; k < kLayers; ++k) {
                const std::uint64_t s = seed * 131 + 17 * k;
                const double base = 0.28 + 0.16 * k, amp = 0.55 - 0.08 * k;
                const double freq = 0.9 + 0.7 * k;
                const double r = base + amp * (fbm1(u * freq + 3.7 * k, s, 7) - 0.5) * 1.6;
                ridge[x * kLayers + k] = static_cast<float>(r);
                // Trees on the two nearest layers: a trunk a few pixels wide, height ~1-4% H.
                const std::uint64_t h = mix(x / 3 ^ (s << 20));
                tree[x * kLayers + k] = (k >= 2 && unit(h) < 0.05) ? float(0.01 + 0.03 * unit(mix(h))) : 0.f;
            }
        }
    }, threads);

    parallel_for(rows, 8, [&](std::size_t rb, std::size_t re) {
        for (std::size_t i = rb; i < re; ++i) {
            const std::uint32_t y = y0 + static_cast<std::uint32_t>(i);
            const double v = double(y) / H;
            std::uint8_t* o = out + i * std::size_t(width) * 3;
            RowFbm<2> stain_field(3, 3, v, seed + 5);
            RowNoise fibre_field(900, v * 60, seed + 11);
            RowFbm<3> cun_field(60, 40, v, seed + 23);
            for (std::uint32_t x = 0; x < width; ++x) {
                const double u = double(x) / H;
                // Paper: warm silk tone, slow stains, fibre streaks and per-pixel grain.
                const double stain = stain_field(u);
                const double fibre = fibre_field(u);
                const std::uint64_t g = key2(x, y, seed);
                const double grain = unit(g) - 0.5;
                double r = 226 - 30 * stain + 10 * fibre + 14 * grain;
                double gr = 210 - 34 * stain + 9 * fibre + 14 * grain;
                double bl = 172 - 40 * stain + 7 * fibre + 14 * grain;
                // Texture strokes (cun): one field shared by the layers, mirrored on odd ones.
                const double cun = cun_field(u);
                for (int k = 0; k < kLayers; ++k) {
                    const double ridge_v = ridge[std::size_t(x) * kLayers + k];
                    const double depth = v - ridge_v;
                    const double t = tree[std::size_t(x) * kLayers + k];
                    double alpha = 0;
                    if (depth >= 0) {
                        // Ink wash: dark at the ridge, fading downward, broken by the strokes.
                        const double d = depth * (6.0 + 3 * k);
                        const double wash = 0.25 + 0.75 / (1 + d + 0.5 * d * d);
                        const double tex = (k & 1) ? 1 - cun : cun;
                        alpha = (0.18 + 0.17 * k) * wash * (0.55 + 0.9 * tex);
                        // Mist: the lower parts of the far layers dissolve.
                        if (k < 2) alpha *= std::clamp(1.0 - depth * 2.5, 0.0, 1.0);
                    } else if (t > 0 && -depth < t) {
                        alpha = 0.85;  // tree trunk above the ridge
                    }
                    // Single-pixel moss dots along the ridge.
                    if (depth > -0.002 && depth < 0.02 && ((g >> (8 * k)) & 63) == 0) alpha = 0.95;
                    alpha = std::clamp(alpha, 0.0, 1.0);
                    r += (28 - r) * alpha;
                    gr += (27 - gr) * alpha;
                    bl += (32 - bl) * alpha;
                }
                // A red seal near the right end.
                const double su = (double(width) - x) / H, sv = v;
                if (su > 0.06 && su < 0.16 && sv > 0.08 && sv < 0.18) {
                    const bool carved = noise2(su * 80, sv * 80, seed + 99) < 0.45;
                    if (!carved) {
                        r += (178 - r) * 0.85;
                        gr += (34 - gr) * 0.85;
                        bl += (30 - bl) * 0.85;
                    }
                }
                o[3 * x + 0] = static_cast<std::uint8_t>(std::clamp(r + 0.5, 0.0, 255.0));
                o[3 * x + 1] = static_cast<std::uint8_t>(std::clamp(gr + 0.5, 0.0, 255.0));
                o[3 * x + 2] = static_cast<std::uint8_t>(std::clamp(bl + 0.5, 0.0, 255.0));
            }
        }
    }, threads);
}

}  // namespace gigascroll

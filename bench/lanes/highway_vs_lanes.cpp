// The sRGB decode of the display's shade step (SrgbCurve::decode) written twice, on the
// project's lane type (common/lanes.h) and on Google Highway (Debian's libhwy-dev, static
// dispatch to the build's widest target), timed over the same codes in alternation, its
// outputs compared bit for bit: the measurement behind docs/lanes.md. Not part of the CMake
// build (Highway is not a dependency); build and run it by hand:
//
//   g++ -std=c++20 -O3 -march=native -mprefer-vector-width=512 -ffp-contract=off -Icpp \
//       bench/lanes/highway_vs_lanes.cpp -o highway_vs_lanes && ./highway_vs_lanes
#include <hwy/highway.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "common/lanes.h"
#include "display/srgb.h"

namespace hn = hwy::HWY_NAMESPACE;
using gigascroll::kWidest;
using gigascroll::Lanes;
using gigascroll::SrgbCurve;

// SrgbCurve::decode's steps on Highway's ops.
HWY_ATTR void decode_highway(const SrgbCurve& curve, const float* in, float* out, std::size_t n) {
    const hn::ScalableTag<float> d;
    const hn::RebindToSigned<decltype(d)> di;
    const std::size_t N = hn::Lanes(d);
    for (std::size_t i = 0; i < n; i += N) {
        const auto c = hn::Min(hn::Max(hn::LoadU(d, in + i), hn::Zero(d)), hn::Set(d, 255.0f));
        const auto s_f = hn::Floor(hn::Mul(c, hn::Set(d, 1.0f / 16.0f)));
        const auto idx = hn::IndicesFromVec(d, hn::ConvertTo(di, s_f));
        const auto t = hn::NegMulAdd(s_f, hn::Set(d, 16.0f), hn::Sub(c, hn::Set(d, 8.0f)));
        auto p = hn::TableLookupLanes(hn::LoadU(d, curve.coef[4]), idx);
        for (int k = 3; k >= 0; --k) p = hn::MulAdd(p, t, hn::TableLookupLanes(hn::LoadU(d, curve.coef[k]), idx));
        const auto linear = hn::Le(c, hn::Set(d, SrgbCurve::kLinearEnd));
        hn::StoreU(hn::IfThenElse(linear, hn::Mul(c, hn::Set(d, SrgbCurve::kLinearScale)), p), d, out + i);
    }
}

void decode_lanes(const SrgbCurve& curve, const float* in, float* out, std::size_t n) {
    using F = Lanes<kWidest>::F;
    for (std::size_t i = 0; i < n; i += kWidest) curve.decode<kWidest>(F::load(in + i)).store(out + i);
}

int main() {
    const SrgbCurve& curve = gigascroll::srgb_curve();
    constexpr std::size_t kCodes = 1 << 14;  // in L1 and L2: the arithmetic, not the memory
    std::vector<float> in(kCodes), a(kCodes), b(kCodes);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> code(0.0f, 255.0f);
    for (float& c : in) c = code(rng);
    // Highway's lanes must be the lane type's (16 floats at AVX-512) for the table lookup.
    if (hn::Lanes(hn::ScalableTag<float>()) != std::size_t(kWidest) || kWidest != 16) {
        std::printf("needs an AVX-512 build (Highway lanes %zu, lane type %d)\n",
                    hn::Lanes(hn::ScalableTag<float>()), kWidest);
        return 1;
    }
    auto time = [&](auto&& f, std::vector<float>& out) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int r = 0; r < 2000; ++r) {
            f(curve, in.data(), out.data(), kCodes);
            asm volatile("" : : "r"(out.data()) : "memory");  // each repetition's stores kept
        }
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / (2000.0 * kCodes) * 1e9;
    };
    std::vector<double> lanes_ns, hwy_ns;
    for (int round = 0; round < 9; ++round) {  // alternated, the medians reported
        lanes_ns.push_back(time(decode_lanes, a));
        hwy_ns.push_back(time(decode_highway, b));
    }
    std::sort(lanes_ns.begin(), lanes_ns.end()), std::sort(hwy_ns.begin(), hwy_ns.end());
    const bool same = std::memcmp(a.data(), b.data(), kCodes * sizeof(float)) == 0;
    std::printf("sRGB decode, ns per code (median of 9): lanes.h %.3f  Highway %.3f  ratio %.3f  outputs %s\n",
                lanes_ns[4], hwy_ns[4], hwy_ns[4] / lanes_ns[4], same ? "bit-equal" : "DIFFER");
    return same ? 0 : 1;
}

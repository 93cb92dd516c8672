// Software virtual-texture sampling (VT-mobile-VR eqs 3-10, Vulkan-SVT's fallback): reads a
// VirtualTexture's page table and physical texture under its read lock. Bilinear uses the
// nearest level, trilinear blends floor(lod) and floor(lod) + 1; clamp-to-edge.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "cache/virtual_texture.h"

namespace gigascroll {

enum class Filter { Bilinear, Trilinear };

// Where samples come from and where results go. lod: per-sample array, or nullptr to use
// lod_scalar for all. level_out (optional): the level that answered (the finer one for
// trilinear), which differs from the one asked for when that tile was not resident.
struct SampleRequest {
    std::uint32_t painting = 0;
    const double* u = nullptr;          // sample i at u[i * uv_stride]
    const double* v = nullptr;          // sample i at v[i * uv_stride]
    std::size_t uv_stride = 1;          // 2 for interleaved (u, v) pairs
    const float* lod = nullptr;
    float lod_scalar = 0.0f;
    std::size_t count = 0;
    Filter filter = Filter::Bilinear;
    float* out = nullptr;               // count x 3, 0..255
    std::int8_t* level_out = nullptr;   // count, may be null
    unsigned threads = 0;
};

// "bilinear" / "trilinear"; InvalidArgument otherwise.
Filter parse_filter(const std::string& name);

// Samples r.count points of painting r.painting on r.threads threads (0 = all cores).
void sample(const VirtualTexture& vt, const SampleRequest& r);
// The same on the calling thread only (r.threads ignored): for callers that already run one
// task per core, such as the display pass.
void sample_serial(const VirtualTexture& vt, const SampleRequest& r);
// The same for a caller that already holds vt.read_lock() for all its calls (the display
// pass takes it once per frame instead of once per run of samples).
void sample_serial_locked(const VirtualTexture& vt, const SampleRequest& r);
// 16 neighbouring samples of one painting as the display pass maps a packet of pixels: lane
// 0's uv in double (a 150k-texel painting needs it) and every lane's offset from it in float
// (a packet spans a few texels, so its offsets keep float's relative precision: 1e-5 texel),
// and the levels of detail.
struct PacketUv {
    double u0 = 0, v0 = 0;
    alignas(64) float du[16] = {}, dv[16] = {};
    alignas(64) float lod[16] = {};
};

// Trilinear on RGB8 slots for 16 samples of one painting at once in SIMD lanes: the display
// pass's packets of 16 neighbouring pixels, whose footprints nearly always lie in one tile
// (or two, across a tile edge) at each level. When they do and those tiles are resident,
// sample16 writes the 16 samples' channels (0..255) to r, g, b and returns true: sample()'s
// taps, texels and blend, the taps in float from the packet's origin, so the footprints'
// weights agree with sample()'s to about 1e-5 and the samples to about 1e-3 of a code (the
// texels are the same unless a position lies that close to a texel's centre, where both
// choices blend to the same value). Otherwise (footprints in three or more tiles, a fallback
// to a coarser tile, levels more than one apart, lanes within two texels of the painting's
// edge, where sample() clamps, paintings of 2^22 texels or more a side, BC1 slots, or a build
// without AVX-512) it writes nothing and returns false, and the caller takes sample() (which
// also reports a painting the texture does not hold). The caller holds vt.read_lock(); one
// object per thread.
class TrilinearLanes {
public:
    TrilinearLanes(const VirtualTexture& vt, std::uint32_t painting);
    ~TrilinearLanes();
    TrilinearLanes(TrilinearLanes&&) noexcept;
    TrilinearLanes& operator=(TrilinearLanes&&) = delete;
    bool sample16(const PacketUv& packet, float* r, float* g, float* b);
    // Whether sample16 can succeed at all (AVX-512 build, RGB8 slots).
    bool enabled() const;
    // sample16 at W lanes a step (common/lanes.h: W = 1, 8 where the build has AVX2, 16
    // where it has AVX-512), with or without the common packet's byte-permuted stretches
    // (AVX-512 VBMI, W = 16): the same samples, for the tests of every width. RGB8 slots, any
    // build.
    template <int W>
    bool sample_lanes(const PacketUv& packet, float* r, float* g, float* b, bool stretches);
    // Forgets the page entries sample16 keeps from call to call (valid only while the caller
    // holds one read lock: a new lock, a new residency).
    void forget_tiles();

private:
    struct State;                   // the constants and the last page entries
    std::unique_ptr<State> state_;  // nullptr: disabled
};

// Trilinear on the calling thread one sample at a time (r.filter ignored): the plain path
// that sample()'s batched trilinear must reproduce, for tests.
void sample_trilinear_reference(const VirtualTexture& vt, const SampleRequest& r);

}  // namespace gigascroll

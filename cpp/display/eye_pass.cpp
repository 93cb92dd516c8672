// One eye's display pass (DisplayPass::render_eye) as named steps over one chunk of rows, in
// the manner of a wavefront renderer: per row, 16-ray packets are traced (trace); a packet
// wholly on one surface with a baked light is deferred (defer) and eight at a time are lit
// (light), mapped to painting coordinates (map), sampled (sample) and shaded (shade); any
// other packet takes the same steps lane by lane at once (take_packet). The right eye first
// releases its claimed pixels on depth edges and takes the kept claims' hits (reuse). Each
// step is a function of EyeChunk over the chunk's arrays (RowScratch, PacketLanes).
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "common/error.h"
#include "common/parallel.h"
#include "common/timing.h"
#include "display/display_pass.h"
#include "display/eye_pass.h"
#include "display/lattice_lanes.h"
#include "display/plane_map.h"
#include "display/primary_rays.h"
#include "display/shade.h"
#include "display/srgb.h"
#include "display/stereo_reuse.h"
#include "sampling/sampler.h"
#include "views/feedback.h"

namespace gigascroll {

using namespace display;

namespace display {
std::uint64_t next_serial() {
    static std::atomic<std::uint64_t> serial{0};
    return serial.fetch_add(1, std::memory_order_relaxed) + 1;
}
}  // namespace display

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Whether the pass reads the baked lattice in 16-lane vectors and defers whole packets (built
// with AVX-512, and the lattice's arrays indexable with 32-bit lanes).
bool lanes16_for(const BakedLattice* baked) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    return baked && LatticeLanes::lanes16(*baked);
#else
    (void)baked;
    return false;
#endif
}

// A painting pixel of the row waiting for its texel: radiance = linear albedo x scale + add.
struct PendingPixel {
    std::uint32_t x;
    int placement;
    Vec3f scale, add;
};

// A packet of 16 pixels of the row wholly on one surface whose light is a baked lattice,
// waiting for the row's end: Embree's hits and the side each lane sees, then its light, and
// on a painting its origin's uv and its lanes' offsets and levels, and its texels.
struct DeferredPacket {
    RTCHit16 hit;  // geomID, primID, u, v and Ng (instID unused)
    alignas(64) std::int32_t back[16];
    LaneLight light;
    PacketUv uv;
    alignas(64) float tex[3][16];
    std::uint32_t x0, n;   // its first pixel's column, its pixels (16 but in a short last packet)
    int placement;        // -1: a room surface
    bool mapped, sampled;  // uv, tex hold them
};
// Deferred packets per stage of the row's end: short enough that a batch's data stay in the
// first-level cache, long enough that the packets' latencies overlap.
constexpr std::size_t kStageBatch = 8;

// A worker's per-row arrays, kept between calls in each thread.
struct RowScratch {
    std::vector<DeferredPacket> packets;  // the deferred packets waiting for run_batch
    std::vector<TrilinearLanes> samplers;  // per placement, for frame samplers_frame
    std::uint64_t samplers_frame = 0, samplers_call = 0;  // their frame, and render_eye call
    std::vector<PendingPixel> pending;
    std::vector<PlaneMap::Row> planes;
    std::vector<std::size_t> plane_of;
    std::vector<double> us, vs;
    std::vector<float> lods, texels;
    std::vector<std::uint32_t> rx;
    std::vector<int> rpl;
    std::vector<std::int32_t> rsrc;
    std::vector<double> rsx;  // their screen x
    std::vector<float> rlod;
    // The right eye's edge release: one row of claimed depths (with an infinite depth either
    // side) and the row minima of the last three claim rows (row r in slot r % 3).
    std::vector<float> depths;
    std::array<std::vector<float>, 3> row_min;
    std::array<std::size_t, 3> row_min_of;

    void fit(std::size_t w, bool reused) {
        if (pending.size() < w) pending.resize(w), us.resize(w), vs.resize(w), lods.resize(w);
        if (packets.size() < kStageBatch) packets.resize(kStageBatch);
        if (texels.size() < 3 * w) texels.resize(3 * w);
        if (reused && rx.size() < w) {
            rx.resize(w), rpl.resize(w), rsrc.resize(w), rlod.resize(w);
            rsx.resize(w);
            depths.resize(w + 2);
            for (auto& m : row_min) m.resize(w);
        }
        row_min_of.fill(~std::size_t(0));  // another frame's claims
    }
};

RowScratch& row_scratch() {
    thread_local RowScratch scratch;
    return scratch;
}

// What every chunk of one eye's pass reads, fixed for the call.
struct EyeFrame {
    const PaintingSceneView& scene;
    const DisplayLighting& lighting;
    const VirtualTexture& vt;
    const Camera& eye;
    const DisplayOptions& o;
    GBuffer& g;
    float* rgb;
    std::uint32_t w;
    // A left eye that the right eye reuses: its hits claim right pixels as they are found
    // (ClaimProjection), and its painting pixels keep their light.
    bool keep_light, keep_hits;
    const BakedLattice* baked;
    bool lanes16;  // the baked lattice read in 16-lane vectors (LatticeLanes::lanes16)
    std::optional<ClaimProjection> claim;
    bool rows_aligned;
    // The right eye: the left eye's buffers, and its claims released row by row just before
    // the row is rendered (the claims of the rows above and below are read, so a worker resets
    // the claims of its chunk's inner rows and the chunks' first and last rows are reset after
    // the pass).
    const GBuffer* left;
    const float* left_rgb;
    std::int32_t* sources;
    std::uint64_t* claims;
    float release_ratio;
    const PlaneMap* maps;  // per placement
    // Screen x of each column's centre (past the last column the last's: cast_rows'
    // whole_tail), and its screen x less that of its packet's first column.
    const double* column_sx;
    const float* column_ds;
    Vec3f origin;
    const SrgbCurve& srgb_decode;
    std::size_t paintings;        // in the virtual texture
    std::uint64_t frame, call;    // for the workers' packet samplers
};

// The counts and stage ticks of one eye, summed over its chunks.
struct EyeTotals {
    std::atomic<std::uint64_t> traced{0}, hits{0}, on_paintings{0}, reused{0};
    std::atomic<std::uint64_t> rays_ticks{0}, vt_ticks{0}, shade_ticks{0}, reuse_ticks{0};
};

// A packet's lanes as the steps of take_packet pass them on: the hits (points, eye-facing
// normals, sides), the hit lanes compacted (lane, placement), the right eye's claims, and the
// painting lanes' columns, uv and levels.
struct PacketLanes {
    alignas(64) float hx[16], hy[16], hz[16], nx[16], ny[16], nz[16];
    alignas(64) std::int32_t back[16];
    alignas(64) int lane_pl[16];  // per hit: its painting placement, -1 for the room
    std::array<std::uint32_t, 16> lane;
    std::uint32_t m = 0;          // hit lanes
    bool dense = false;           // a whole packet on one surface
    alignas(64) std::uint32_t claim_target[16];
    alignas(64) float claim_depth[16];
    alignas(64) int hit[16];
    alignas(64) double psx[16], pu[16], pv[16];
    alignas(64) float plod[16];
    alignas(64) std::uint32_t pj[16];
    alignas(64) int ppl[16];
    std::uint32_t np = 0;          // painting lanes
};

// One chunk of rows [rb, re) of one eye: the steps of the pass over the chunk's arrays.
class EyeChunk : EyeFrame {
public:
    EyeChunk(const EyeFrame& f, std::size_t rb, std::size_t re);
    // trace: the chunk's rows cast in packets, each packet and row through the steps below.
    void trace();
    void add_to(EyeTotals& t) const;

private:
    // Per packet: deferred whole, or through the lane by lane steps at once.
    [[gnu::always_inline]] inline void take_packet(std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                                            const RTCRayHit16& h);
    [[gnu::always_inline]] inline void start_row(std::size_t row);
    [[gnu::always_inline]] inline const PlaneMap::Row& plane(int pl);
    [[gnu::always_inline]] inline void lap(std::uint64_t& acc);
    // hits: the side each hit sees, their points and eye-facing normals.
    static void back_sides(const RTCRayHit16& h, std::int32_t* back);
    [[gnu::always_inline]] inline void hit_points(const RTCRayHit16& h, const std::int32_t* back, bool with_normals,
                                                  float* hx, float* hy, float* hz, float* nx, float* ny,
                                                  float* nz) const;
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    // defer: a whole packet's hits kept (and claims made), the rest waiting for run_batch.
    void defer(std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h, unsigned g0);
    void keep_hits_and_claim(std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h,
                             unsigned g0, const std::int32_t* back);
    // The deferred packets, stage by stage.
    void run_batch();
    void light_batch(std::size_t count);
    void map_batch(std::size_t count);
    void sample_batch(std::size_t count);
    void shade_batch(std::size_t count);
    void pend16(const DeferredPacket& d, const double* u, const double* v, const float* lod);
#endif
    // Lane by lane: every packet but the deferred ones.
    [[gnu::noinline]] void other_packet(std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                                        const RTCRayHit16& h);
    void gather_lanes(PacketLanes& pk, std::size_t row_start, std::uint32_t n, const int* valid, const RTCRayHit16& h);
    void light_lanes(PacketLanes& pk, const RTCRayHit16& h);
    void map_lanes(PacketLanes& pk, std::uint32_t i0);
    void shade_room_lanes(const PacketLanes& pk, std::size_t row_start);
    void queue_painting_lanes(const PacketLanes& pk, std::size_t row_start, std::uint32_t i0);
    // reuse: the right eye's edge release and its claimed pixels.
    void release_row(std::size_t row);
    void reuse_row(std::size_t row);
    bool reuse_dense_run(std::size_t row, std::uint32_t x0, std::size_t& reused_here, std::size_t& copied);
    std::size_t reuse_levels(std::size_t nr);
    void reuse_resample(std::size_t row, std::size_t nr, std::size_t& copied);
    // The row's end: its pending painting pixels sampled and shaded.
    void finish_row(std::size_t row);
    void sample_pending();
    void shade_pending(std::size_t row);

    std::size_t rb, re;
    RowScratch& sc;
    std::size_t pending_count = 0;
    std::size_t copied_count = 0;  // the row's reused pixels that kept the left radiance
    std::size_t current_row = ~std::size_t(0);
    Vec3d row_direction;  // D . forward = 1 at the row's centre, screen x 0
    std::uint64_t traced_count = 0, hit_count = 0, painting_count = 0, reused_count = 0;
    // Thread time per stage: laps between the stages, taken on every kTimedRow-th row only
    // (split_wall needs only their proportions; a clock read per stage and packet cost a few
    // percent of the pass).
    static constexpr std::size_t kTimedRow = 8;
    std::uint64_t t_rays = 0, t_vt = 0, t_shade = 0, t_reuse = 0;
    bool timed;
    std::uint64_t mark;
    std::array<LightQuery, 16> queries;
    std::array<SurfaceLight, 16> lights;
    LaneLight lane_light;
    LatticeLanes lattice;
    std::size_t batch_count = 0;  // deferred packets waiting in sc.packets
    alignas(64) int all_hits[16];
};

EyeChunk::EyeChunk(const EyeFrame& f, std::size_t rb_, std::size_t re_)
    : EyeFrame(f), rb(rb_), re(re_), sc(row_scratch()), timed(rb_ % kTimedRow == 0), mark(stage_ticks()) {
    // The row's painting pixels waiting for their texels (at most one per column, so arrays
    // of the row's width and a count: no push_back's capacity test per pixel), in this
    // thread's scratch (allocating the arrays per call cost page faults).
    sc.fit(w, left != nullptr);
    // Per placement, its plane map's Row for the row plane_of[pl] (made when the row first
    // needs it: a room of 40 paintings shows a few in most rows).
    sc.planes.resize(scene.paintings.size());
    sc.plane_of.assign(scene.paintings.size(), ~std::size_t(0));
    std::fill_n(all_hits, 16, -1);
#if defined(__AVX512F__)
    // Per placement, the sampler of whole packets on one painting (TrilinearLanes), made once
    // per frame and thread (the frame's eyes share the scene and the VT); they forget their
    // cached page entries once per call (this call's read lock).
    if (sc.samplers_frame != frame) {
        sc.samplers.clear();
        for (const PaintingPlacement& pp : scene.paintings) sc.samplers.emplace_back(vt, pp.painting);
        sc.samplers_frame = frame, sc.samplers_call = call;
    } else if (sc.samplers_call != call) {
        for (TrilinearLanes& s : sc.samplers) s.forget_tiles();
        sc.samplers_call = call;
    }
#endif
}

void EyeChunk::lap(std::uint64_t& acc) {
    if (!timed) return;
    const std::uint64_t now = stage_ticks();
    acc += now - mark;
    mark = now;
}

void EyeChunk::start_row(std::size_t row) {
    if (row == current_row) return;
    current_row = row;
    // The row's directions D = row_direction + screen x along right.
    row_direction = eye.forward + eye.screen_y(row + 0.5) * eye.up;
    pending_count = 0;
}

const PlaneMap::Row& EyeChunk::plane(int pl) {
    const std::size_t p = std::size_t(pl);
    if (sc.plane_of[p] != current_row) {
        sc.planes[p] = maps[p].row(row_direction, eye.right);
        sc.plane_of[p] = current_row;
    }
    return sc.planes[p];
}

void EyeChunk::trace() {
    cast_rows(
        scene.handle, eye, rb, re, sources, lanes16, [&](std::size_t row) { release_row(row); },
        [&](std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid, const RTCRayHit16& h)
            __attribute__((always_inline)) { take_packet(row, i0, n, valid, h); },
        [&](std::size_t row) { finish_row(row); });
}

void EyeChunk::add_to(EyeTotals& t) const {
    t.traced.fetch_add(traced_count, std::memory_order_relaxed);
    t.hits.fetch_add(hit_count, std::memory_order_relaxed);
    t.on_paintings.fetch_add(painting_count, std::memory_order_relaxed);
    t.rays_ticks.fetch_add(t_rays, std::memory_order_relaxed);
    t.vt_ticks.fetch_add(t_vt, std::memory_order_relaxed);
    t.shade_ticks.fetch_add(t_shade, std::memory_order_relaxed);
    t.reuse_ticks.fetch_add(t_reuse, std::memory_order_relaxed);
    t.reused.fetch_add(reused_count, std::memory_order_relaxed);
}

void EyeChunk::take_packet(std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                           const RTCRayHit16& h) {
    lap(t_rays);
    start_row(row);
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    if (lanes16) {  // (a short last packet casts all 16 lanes: whole_tail)
        const unsigned g0 = h.hit.geomID[0];
        using I = Lanes<kWidest>::I;
        bool one_geometry = g0 != kNoHit;  // every lane cast, all on lane 0's geometry
        for (int k = 0; k < 16 && one_geometry; k += kWidest)
            one_geometry = all<kWidest>(nonzero(I::load(valid + k)) & (I::load(h.hit.geomID + k) == I(std::int32_t(g0))));
        if (one_geometry) {
            defer(row, i0, n, h, g0);
            return;
        }
    }
#endif
    other_packet(row, i0, n, valid, h);
}

// The side of each of a packet's hits the eye sees (back: the ray runs along Embree's
// geometric normal), in SIMD lanes (all 16, hit or not: the lanes are independent).
void EyeChunk::back_sides(const RTCRayHit16& h, std::int32_t* back) {
    for (std::uint32_t k = 0; k < 16; ++k)
        back[k] = -std::int32_t(h.hit.Ng_x[k] * h.ray.dir_x[k] + h.hit.Ng_y[k] * h.ray.dir_y[k] +
                                    h.hit.Ng_z[k] * h.ray.dir_z[k] > 0);
}

// The packet's hit points, and their eye-facing unit normals (with_normals), in lanes.
void EyeChunk::hit_points(const RTCRayHit16& h, const std::int32_t* back, bool with_normals, float* hx,
                          float* hy, float* hz, float* nx, float* ny, float* nz) const {
    for (std::uint32_t k = 0; k < 16; ++k) {
        const float t = h.ray.tfar[k];
        hx[k] = origin.x + h.ray.dir_x[k] * t, hy[k] = origin.y + h.ray.dir_y[k] * t;
        hz[k] = origin.z + h.ray.dir_z[k] * t;
    }
    if (!with_normals) return;
    alignas(64) float inv_len[16];
    for (std::uint32_t k = 0; k < 16; ++k) {
        const float gx = h.hit.Ng_x[k], gy = h.hit.Ng_y[k], gz = h.hit.Ng_z[k];
        inv_len[k] = gx * gx + gy * gy + gz * gz;
    }
    inverse_sqrt_16(inv_len);
    for (std::uint32_t k = 0; k < 16; ++k) {
        const float gx = h.hit.Ng_x[k] * inv_len[k], gy = h.hit.Ng_y[k] * inv_len[k],
                    gz = h.hit.Ng_z[k] * inv_len[k];
        nx[k] = back[k] ? -gx : gx, ny[k] = back[k] ? -gy : gy, nz[k] = back[k] ? -gz : gz;
    }
}

#if defined(__AVX512F__) && defined(__AVX512DQ__)
// A packet wholly on one surface with its light in the baked lattice (nearly every packet):
// its hits kept (and the right eye's claims made) now, the rest deferred to run_batch with the
// next packets (done here, one packet after another between Embree's calls, each stage's
// latencies stalled the packet).
void EyeChunk::defer(std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h, unsigned g0) {
    DeferredPacket& d = sc.packets[batch_count++];
    back_sides(h, d.back);
    std::copy_n(h.hit.geomID, 16, d.hit.geomID), std::copy_n(h.hit.primID, 16, d.hit.primID);
    std::copy_n(h.hit.u, 16, d.hit.u), std::copy_n(h.hit.v, 16, d.hit.v);
    std::copy_n(h.hit.Ng_x, 16, d.hit.Ng_x), std::copy_n(h.hit.Ng_y, 16, d.hit.Ng_y);
    std::copy_n(h.hit.Ng_z, 16, d.hit.Ng_z);
    d.x0 = i0, d.n = n, d.placement = g0 < scene.geom_placement.size() ? scene.geom_placement[g0] : -1;
    traced_count += n, hit_count += n;
    if (keep_hits || claim) keep_hits_and_claim(row, i0, n, h, g0, d.back);
    if (batch_count == kStageBatch) run_batch();
}

void EyeChunk::keep_hits_and_claim(std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h,
                                   unsigned g0, const std::int32_t* back) {
    alignas(64) float hx[16], hy[16], hz[16], nx[16], ny[16], nz[16];
    hit_points(h, back, bool(claim), hx, hy, hz, nx, ny, nz);
    const std::size_t row_start = row * w + i0;
    if (keep_hits) {
        std::fill_n(g.geom.data() + row_start, n, g0);
        Vec3f* __restrict const p_out = g.p.data() + row_start;
        for (std::uint32_t k = 0; k < n; ++k) p_out[k].x = hx[k], p_out[k].y = hy[k], p_out[k].z = hz[k];
    }
    if (claim) {
        alignas(64) std::uint32_t claim_target[16];
        alignas(64) float claim_depth[16];
        alignas(64) int hit[16];
        for (std::uint32_t k = 0; k < 16; ++k) hit[k] = k < n ? -1 : 0;
        lap(t_shade);
        claim->project16(hx, hy, hz, nx, ny, nz, hit, claim_target, claim_depth);
        claim->claim16(claim_target, claim_depth, std::uint32_t(row_start),
                       claim->claim_rows(rows_aligned, row, rb, re));
        lap(t_reuse);
    }
}

// The deferred packets, stage by stage (each stage a short loop over the batch's independent
// packets, so their latencies overlap; the batch's data stay in the first-level cache).
void EyeChunk::run_batch() {
    const std::size_t count = batch_count;
    batch_count = 0;
    light_batch(count);
    lap(t_shade);
    map_batch(count);
    sample_batch(count);
    lap(t_vt);
    shade_batch(count);
    lap(t_shade);
}

// light: each packet's light (the baked lattice in lanes), shaded at once on a room surface.
void EyeChunk::light_batch(std::size_t count) {
    float* __restrict const lod_row = g.lod.data() + current_row * w;
    float* __restrict const rgb_row = rgb + 3 * current_row * w;
    for (std::size_t q = 0; q < count; ++q) {
        DeferredPacket& d = sc.packets[q];
        LaneLight& L = d.light;
        if (!lattice.light16_cells(*baked, d.hit, d.back, d.placement < 0, L)) {
            lattice.locate16(*baked, d.hit, all_hits, d.back);
            lattice.blend16(*baked, L);
        }
        if (d.placement < 0) shade_room_packet(L, rgb_row + 3 * std::size_t(d.x0), lod_row + d.x0, d.n);
    }
}

// A packet's 16 pixels queued as pending pixels at uv (u, v) and level lod.
void EyeChunk::pend16(const DeferredPacket& d, const double* u, const double* v, const float* lod) {
    float* __restrict const lod_row = g.lod.data() + current_row * w;
    Vec3f* __restrict const scale_row = keep_light ? g.scale.data() + current_row * w : nullptr;
    Vec3f* __restrict const add_row = keep_light ? g.add.data() + current_row * w : nullptr;
    GS_CHECK(pending_count + d.n <= w);  // one pixel per column and row
    for (std::uint32_t k = 0; k < d.n; ++k) {
        const std::size_t pc = pending_count++, x = d.x0 + k;
        PendingPixel& pp = sc.pending[pc];
        pp.x = std::uint32_t(x), pp.placement = d.placement;
        pp.scale = Vec3f{d.light.E[0][k], d.light.E[1][k], d.light.E[2][k]} * kInvPi;
        pp.add = Vec3f{d.light.M[0][k], d.light.M[1][k], d.light.M[2][k]};
        sc.us[pc] = u[k], sc.vs[pc] = v[k], sc.lods[pc] = lod[k];
        lod_row[x] = lod[k];
        if (keep_light) scale_row[x] = pp.scale, add_row[x] = pp.add;
    }
}

// map: a painting packet's origin uv, offsets and levels (PlaneMap::map_packet); one the
// sampler or the map declines joins the row's pending pixels.
void EyeChunk::map_batch(std::size_t count) {
    for (std::size_t q = 0; q < count; ++q) {
        DeferredPacket& d = sc.packets[q];
        d.mapped = d.sampled = false;
        if (d.placement < 0) continue;
        const std::size_t pl = std::size_t(d.placement);
        d.mapped = sc.samplers[pl].enabled() &&
                   maps[pl].map_packet(plane(d.placement), column_sx[d.x0], column_ds + d.x0, o.lod_bias, d.uv);
        if (d.mapped) continue;
        // Not a normal footprint (a grazing view): map_columns patches it in double.
        alignas(64) double u[16], v[16];
        alignas(64) float lod[16];
        maps[pl].map_columns<true>(plane(d.placement), 16, column_sx + d.x0, u, v, lod);
        for (std::uint32_t k = 0; k < 16; ++k) lod[k] = sampled_lod(lod[k], o.lod_bias);
        pend16(d, u, v, lod);
    }
}

// sample: a mapped packet's texels (TrilinearLanes).
void EyeChunk::sample_batch(std::size_t count) {
    for (std::size_t q = 0; q < count; ++q) {
        DeferredPacket& d = sc.packets[q];
        if (!d.mapped) continue;
        d.sampled = sc.samplers[std::size_t(d.placement)].sample16(d.uv, d.tex[0], d.tex[1], d.tex[2]);
        if (d.sampled) continue;
        alignas(64) double u[16], v[16];
        for (std::uint32_t k = 0; k < 16; ++k) u[k] = d.uv.u0 + d.uv.du[k], v[k] = d.uv.v0 + d.uv.dv[k];
        pend16(d, u, v, d.uv.lod);
    }
}

// shade: a sampled packet's radiance, its levels, and its light kept for the right eye.
void EyeChunk::shade_batch(std::size_t count) {
    float* __restrict const lod_row = g.lod.data() + current_row * w;
    float* __restrict const rgb_row = rgb + 3 * current_row * w;
    Vec3f* __restrict const scale_row = keep_light ? g.scale.data() + current_row * w : nullptr;
    Vec3f* __restrict const add_row = keep_light ? g.add.data() + current_row * w : nullptr;
    for (std::size_t q = 0; q < count; ++q) {
        const DeferredPacket& d = sc.packets[q];
        if (!d.sampled) continue;
        shade_packet(d.tex, d.light.E, d.light.M, o, srgb_decode, rgb_row + 3 * std::size_t(d.x0), d.n);
        for (int k = 0; k < 16; k += kWidest)
            store_first(Lanes<kWidest>::F::load(d.uv.lod + k), lod_row + d.x0 + k, lanes_of(d.n, k));
        if (keep_light)
            for (std::uint32_t k = 0; k < d.n; ++k) {
                Vec3f& sc_k = scale_row[d.x0 + k];
                sc_k.x = d.light.E[0][k] * kInvPi, sc_k.y = d.light.E[1][k] * kInvPi, sc_k.z = d.light.E[2][k] * kInvPi;
                Vec3f& add_k = add_row[d.x0 + k];
                add_k.x = d.light.M[0][k], add_k.y = d.light.M[1][k], add_k.z = d.light.M[2][k];
            }
        painting_count += d.n;
    }
}
#endif

// Every packet but the deferred ones: the side each hit sees; the hit points and eye-facing
// unit normals only where something reads them (the G-buffer, the right eye's claims, a
// lighting that is not a baked lattice). Out of line, so that the common packet's test and
// deferral sit in cast_rows' loop without this body's register saves.
void EyeChunk::other_packet(std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                            const RTCRayHit16& h) {
    PacketLanes pk;  // on this call's stack: no store through the chunk's pointers can reach it
    back_sides(h, pk.back);
    if (keep_hits || claim || !baked)
        hit_points(h, pk.back, claim || !baked, pk.hx, pk.hy, pk.hz, pk.nx, pk.ny, pk.nz);
    const std::size_t row_start = row * w + i0;
    gather_lanes(pk, row_start, n, valid, h);
    // The right eye's claims, projected while the hits are in registers and made after the
    // lighting call (their cache lines fetched meanwhile).
    for (std::uint32_t k = 0; k < 16; ++k) pk.hit[k] = k < n && valid[k] && h.hit.geomID[k] != kNoHit ? -1 : 0;
    if (claim && pk.m) {
        lap(t_shade);
        claim->project16(pk.hx, pk.hy, pk.hz, pk.nx, pk.ny, pk.nz, pk.hit, pk.claim_target, pk.claim_depth);
        lap(t_reuse);
    }
    light_lanes(pk, h);
    lap(t_shade);
    if (claim && pk.m) {
        claim->claim16(pk.claim_target, pk.claim_depth, std::uint32_t(row_start),
                       claim->claim_rows(rows_aligned, row, rb, re));
        lap(t_reuse);
    }
    map_lanes(pk, i0);
    if (pk.m && lanes16) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
        lattice.blend16(*baked, lane_light);
#endif
    } else if (pk.m && baked) {
        lattice.blend(*baked, lane_light);
    }
    shade_room_lanes(pk, row_start);
    queue_painting_lanes(pk, row_start, i0);
    lap(t_vt);
}

// The packet's hit lanes: a whole packet on one surface (most packets, with baked light)
// needs no compaction, and on a painting no gathering of the painting lanes; otherwise the
// hit lanes in order, misses shaded black, and for a lighting that is not a baked lattice
// its queries.
void EyeChunk::gather_lanes(PacketLanes& pk, std::size_t row_start, std::uint32_t n, const int* valid, const RTCRayHit16& h) {
    // The buffers and the counts in restrict locals: through the members, every store forced
    // their reload (it might alias them).
    unsigned* __restrict const geom_out = g.geom.data();
    Vec3f* __restrict const p_out = g.p.data();
    float* __restrict const lod_out = g.lod.data();
    float* __restrict const rgb_out = rgb;
    const int* __restrict const placement = scene.geom_placement.data();
    const std::size_t placements = scene.geom_placement.size();
    std::uint32_t m = 0, traced_here = 0;
    const unsigned g0 = h.hit.geomID[0];
    bool dense = n == 16 && baked && g0 != kNoHit;
    if (dense) {
        int all = -1;
        for (std::uint32_t k = 0; k < 16; ++k) all &= valid[k] & -int(h.hit.geomID[k] == g0);
        dense = all != 0;
    }
    if (dense) {
        const int pl0 = g0 < placements ? placement[g0] : -1;
        if (keep_hits)
            for (std::uint32_t k = 0; k < 16; ++k) {
                geom_out[row_start + k] = g0;
                Vec3f& gp = p_out[row_start + k];
                gp.x = pk.hx[k], gp.y = pk.hy[k], gp.z = pk.hz[k];
            }
        for (std::uint32_t k = 0; k < 16; ++k) pk.lane_pl[k] = pl0, pk.lane[k] = k;
        m = traced_here = 16;
    }
    for (std::uint32_t k = 0; k < n && !dense; ++k) {
        if (!valid[k]) continue;
        ++traced_here;
        const std::size_t i = row_start + k;
        const unsigned geom = h.hit.geomID[k];
        if (keep_hits) geom_out[i] = geom;
        if (geom == kNoHit) {
            rgb_out[3 * i] = rgb_out[3 * i + 1] = rgb_out[3 * i + 2] = 0.0f;
            lod_out[i] = kNaN;
            continue;
        }
        // Component stores: a Vec3f copied through the stack stalled on store forwarding (a
        // 12-byte object read back as 8 + 4 bytes).
        if (keep_hits) {
            Vec3f& gp = p_out[i];
            gp.x = pk.hx[k], gp.y = pk.hy[k], gp.z = pk.hz[k];
        }
        if (!baked) {
            LightQuery& q = queries[m];
            q.geom = geom, q.prim = h.hit.primID[k], q.b1 = h.hit.u[k], q.b2 = h.hit.v[k];
            q.p.x = pk.hx[k], q.p.y = pk.hy[k], q.p.z = pk.hz[k];
            q.n.x = pk.nx[k], q.n.y = pk.ny[k], q.n.z = pk.nz[k];
        }
        pk.lane_pl[m] = geom < placements ? placement[geom] : -1;
        pk.lane[m++] = k;
    }
    traced_count += traced_here;
    hit_count += m;
    pk.m = m, pk.dense = dense;
}

// light: the hits' light per lane: the baked lattice read in lanes (its points fetched now,
// blended after the plane map), else the lighting's batch call, its records spread onto
// their lanes.
void EyeChunk::light_lanes(PacketLanes& pk, const RTCRayHit16& h) {
    LaneLight& ll = lane_light;
    const std::uint32_t m = pk.m;
    if (m && lanes16) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
        lattice.locate16(*baked, h.hit, pk.hit, pk.back);
#endif
    } else if (m && baked) {
        lattice.locate(*baked, h.hit, pk.hit, pk.back);
    } else if (m) {
        lighting.light_batch(queries.data(), m, lights.data());
        for (std::uint32_t j = 0; j < m; ++j) {
            const SurfaceLight& sl = lights[j];
            const std::uint32_t k = pk.lane[j];
            ll.E[0][k] = sl.irradiance.x, ll.E[1][k] = sl.irradiance.y, ll.E[2][k] = sl.irradiance.z;
            ll.a[0][k] = sl.albedo.x, ll.a[1][k] = sl.albedo.y, ll.a[2][k] = sl.albedo.z;
            ll.M[0][k] = sl.emission.x, ll.M[1][k] = sl.emission.y, ll.M[2][k] = sl.emission.z;
        }
    }
}

// map: the painting lanes mapped to uv and level from their columns' screen x in runs of one
// painting, in SIMD lanes (PlaneMap::map_columns).
void EyeChunk::map_lanes(PacketLanes& pk, std::uint32_t i0) {
    std::uint32_t np = 0;
    const bool dense_painting = pk.dense && pk.lane_pl[0] >= 0;
    if (dense_painting) {
        for (std::uint32_t k = 0; k < 16; ++k) pk.pj[k] = k, pk.ppl[k] = pk.lane_pl[0];
        maps[std::size_t(pk.lane_pl[0])].map_columns<true>(plane(pk.lane_pl[0]), 16, column_sx + i0, pk.pu, pk.pv,
                                                           pk.plod);
        np = 16;
    }
    for (std::uint32_t j = 0; j < pk.m && !dense_painting; ++j) {
        const std::uint32_t k = pk.lane[j];
        const int pl = pk.lane_pl[j];
        if (pl < 0) continue;
        pk.psx[np] = column_sx[i0 + k];
        pk.pj[np] = j, pk.ppl[np] = pl;
        ++np;
    }
    for (std::uint32_t r0 = 0; r0 < np && !dense_painting;) {
        const int pl = pk.ppl[r0];
        std::uint32_t r1 = r0 + 1;
        while (r1 < np && pk.ppl[r1] == pl) ++r1;
        maps[std::size_t(pl)].map_columns<true>(plane(pl), r1 - r0, pk.psx + r0, pk.pu + r0, pk.pv + r0,
                                                pk.plod + r0);
        r0 = r1;
    }
    pk.np = np;
}

// shade: the room lanes' radiance, albedo x irradiance / pi + emission.
void EyeChunk::shade_room_lanes(const PacketLanes& pk, std::size_t row_start) {
    const LaneLight& ll = lane_light;
    float* __restrict const lod_out = g.lod.data();
    float* __restrict const rgb_out = rgb;
    std::uint32_t m = pk.m;
    const bool dense_painting = pk.dense && pk.lane_pl[0] >= 0;
#if defined(__AVX512F__)
    // A whole packet on one room surface: the loop below in lanes.
    if (pk.dense && !dense_painting) {
        shade_room_packet(ll, rgb_out + 3 * row_start, lod_out + row_start);
        m = 0;  // nothing left for the loop below
    }
#endif
    for (std::uint32_t j = 0; j < m && !dense_painting; ++j) {
        if (pk.lane_pl[j] >= 0) continue;
        const std::uint32_t k = pk.lane[j];
        const std::size_t i = row_start + k;
        const Vec3f L = Vec3f{ll.a[0][k], ll.a[1][k], ll.a[2][k]} * Vec3f{ll.E[0][k], ll.E[1][k], ll.E[2][k]} * kInvPi +
                        Vec3f{ll.M[0][k], ll.M[1][k], ll.M[2][k]};
        rgb_out[3 * i] = L.x, rgb_out[3 * i + 1] = L.y, rgb_out[3 * i + 2] = L.z;
        lod_out[i] = kNaN;
    }
}

// The painting lanes' levels (with the bias; a non-finite level samples level 0) stored,
// their texels queued, and their light kept for the right eye.
void EyeChunk::queue_painting_lanes(const PacketLanes& pk, std::size_t row_start, std::uint32_t i0) {
    const LaneLight& ll = lane_light;
    float* __restrict const lod_out = g.lod.data();
    Vec3f* __restrict const scale_out = keep_light ? g.scale.data() : nullptr;
    Vec3f* __restrict const add_out = keep_light ? g.add.data() : nullptr;
    PendingPixel* __restrict const pend = sc.pending.data();
    double* __restrict const us_out = sc.us.data();
    double* __restrict const vs_out = sc.vs.data();
    float* __restrict const lods_out = sc.lods.data();
    const float bias = o.lod_bias;
    const std::uint32_t np = pk.np;
    std::size_t pc = pending_count;
    GS_CHECK(pc + np <= w);  // one pixel per column and row
    for (std::uint32_t q = 0; q < np; ++q) {
        const std::uint32_t j = pk.pj[q], k = pk.lane[j];
        const std::size_t i = row_start + k;
        const Vec3f scale = Vec3f{ll.E[0][k], ll.E[1][k], ll.E[2][k]} * kInvPi;
        const Vec3f emission{ll.M[0][k], ll.M[1][k], ll.M[2][k]};
        if (keep_light) {
            scale_out[i].x = scale.x, scale_out[i].y = scale.y, scale_out[i].z = scale.z;
            add_out[i].x = emission.x, add_out[i].y = emission.y, add_out[i].z = emission.z;
        }
        const float lod = sampled_lod(pk.plod[q], bias);
        lod_out[i] = lod;
        PendingPixel& pp = pend[pc];
        pp.x = i0 + k, pp.placement = pk.ppl[q];
        pp.scale = scale, pp.add = emission;
        us_out[pc] = pk.pu[q], vs_out[pc] = pk.pv[q], lods_out[pc] = lod;
        ++pc;
    }
    pending_count = pc;
}

// reuse (the right eye): the edge release of the row's claims (their sources, the packets'
// skip mask) from the row minima of the claim rows above, at and below.
void EyeChunk::release_row(std::size_t row) {
    if (!left) return;
    const std::size_t h = eye.height;
    const float* m[3];
    for (int d = 0; d < 3; ++d) {
        const std::size_t r = std::min(h - 1, std::max(row + d, std::size_t(1)) - 1);
        std::vector<float>& slot = sc.row_min[r % 3];
        if (sc.row_min_of[r % 3] != r) {
            claimed_row_min(claims + r * w, w, sc.depths.data(), slot.data());
            sc.row_min_of[r % 3] = r;
        }
        m[d] = slot.data();
    }
    // A chunk's first and last claim rows are read by the chunks beside it: reset later.
    reused_count += release_claims(claims + row * w, m[0], m[1], m[2], w, release_ratio, sources + row * w,
                                   rb < row && row + 1 < re);
    lap(t_reuse);
}

// The row's end: the right eye's claimed pixels, the deferred packets left, and the pending
// painting pixels sampled in runs and shaded.
void EyeChunk::finish_row(std::size_t row) {
    lap(t_rays);
    start_row(row);
    if (left) reuse_row(row);
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    if (batch_count) run_batch();
#endif
    sample_pending();
    lap(t_vt);
    shade_pending(row);
    painting_count += pending_count + copied_count;
    copied_count = 0;
    lap(t_shade);
    timed = (row + 1) % kTimedRow == 0;
    if (timed) mark = stage_ticks();
}

// reuse: the right eye's claimed pixels take the left hit and its light, and the level of
// this eye at the pixel (along its centre ray, as a traced pixel's); the painting pixels'
// levels in SIMD lanes per run of one painting (PlaneMap::map_columns, as the left eye's
// packets).
void EyeChunk::reuse_row(std::size_t row) {
    const std::int32_t* __restrict src = sources + row * w;
    const unsigned* __restrict lgeom = left->geom.data();
    const float* __restrict lrgb = left_rgb;
    unsigned* __restrict geom_out = g.geom.data() + row * w;
    float* __restrict lod_out = g.lod.data() + row * w;
    float* __restrict rgb_out = rgb + 3 * row * w;
    const int* __restrict placement = scene.geom_placement.data();
    const std::size_t placements = scene.geom_placement.size();
    std::uint32_t* __restrict rxs = sc.rx.data();
    int* __restrict rpls = sc.rpl.data();
    std::int32_t* __restrict rsrcs = sc.rsrc.data();
    std::size_t nr = 0, reused_here = 0, copied = 0;
    for (std::uint32_t x0 = 0; x0 < w; x0 += 16) {
        const std::uint32_t x1 = std::min(w, x0 + 16);
        if (x1 - x0 == 16 && reuse_dense_run(row, x0, reused_here, copied)) continue;
        for (std::uint32_t x = x0; x < x1; ++x) {
            const std::int32_t s = src[x];
            if (s < 0) continue;
            ++reused_here;
            const std::size_t si = std::size_t(s);
            const unsigned geom = lgeom[si];
            geom_out[x] = geom;  // the point stays in the left buffer (hit_points)
            const int pl = geom < placements ? placement[geom] : -1;
            if (pl < 0) {  // the left eye's radiance: the same light, the same albedo
                rgb_out[3 * x] = lrgb[3 * si], rgb_out[3 * x + 1] = lrgb[3 * si + 1];
                rgb_out[3 * x + 2] = lrgb[3 * si + 2];
                lod_out[x] = kNaN;
                continue;
            }
            rxs[nr] = x, rpls[nr] = pl, rsrcs[nr] = s;
            ++nr;
        }
    }
    hit_count += reused_here;
    reuse_levels(nr);
    reuse_resample(row, nr, copied);
    copied_count += copied;
}

// 16 pixels reusing 16 consecutive left pixels on one surface (most of a row: the disparity
// changes slowly) are copied whole: the left radiance, and on a painting the levels in SIMD
// lanes and the copy if all agree with the left eye's (else false: they go the per-pixel way,
// as every other pixel).
bool EyeChunk::reuse_dense_run(std::size_t row, std::uint32_t x0, std::size_t& reused_here, std::size_t& copied) {
    const std::int32_t* __restrict src = sources + row * w;
    const unsigned* __restrict lgeom = left->geom.data();
    const float* __restrict llod = left->lod.data();
    const std::int32_t s0 = src[x0];
    if (s0 < 0) return false;
    int same = -1;
    for (std::uint32_t k = 0; k < 16; ++k) same &= -int(src[x0 + k] == s0 + std::int32_t(k));
    if (!same) return false;
    const std::size_t si = std::size_t(s0);
    const unsigned geom = lgeom[si];
    for (std::uint32_t k = 0; k < 16; ++k) same &= -int(lgeom[si + k] == geom);
    if (!same) return false;
    const int pl = geom < scene.geom_placement.size() ? scene.geom_placement[geom] : -1;
    alignas(64) float lod16[16];
    if (pl >= 0) {
        maps[std::size_t(pl)].map_columns<false>(plane(pl), 16, column_sx + x0, nullptr, nullptr, lod16);
        for (std::uint32_t k = 0; k < 16; ++k) {
            lod16[k] = sampled_lod(lod16[k], o.lod_bias);
            same &= -int(std::abs(llod[si + k] - lod16[k]) <= o.reuse_lod_tolerance);
        }
        if (!same) return false;
        copied += 16;
    } else {
        std::fill_n(lod16, 16, kNaN);
    }
    std::fill_n(g.geom.data() + row * w + x0, 16, geom);  // the points stay in the left buffer
    std::copy_n(lod16, 16, g.lod.data() + row * w + x0);
    std::copy_n(left_rgb + 3 * si, 48, rgb + 3 * (row * w + x0));
    reused_here += 16;
    return true;
}

// The reused painting pixels' levels along this eye's ray through the pixel's centre, as the
// packets compute a traced pixel's (D = row direction + screen x along right, D . forward =
// 1): no point gathered and no division per pixel.
std::size_t EyeChunk::reuse_levels(std::size_t nr) {
    const std::uint32_t* __restrict rxs = sc.rx.data();
    const int* __restrict rpls = sc.rpl.data();
    double* __restrict sxs = sc.rsx.data();
    for (std::size_t k = 0; k < nr; ++k) sxs[k] = column_sx[rxs[k]];
    float* __restrict lods_r = sc.rlod.data();
    for (std::size_t r0 = 0; r0 < nr;) {
        const int pl = rpls[r0];
        std::size_t r1 = r0 + 1;
        while (r1 < nr && rpls[r1] == pl) ++r1;
        maps[std::size_t(pl)].map_columns<false>(plane(pl), r1 - r0, sxs + r0, nullptr, nullptr, lods_r + r0);
        r0 = r1;
    }
    return nr;
}

// A reused point whose level here is the left eye's to within the tolerance keeps the left
// eye's sample (the trilinear blend would move by less than that fraction of the two levels'
// difference); with the left eye's texel, light and shading its radiance is the left pixel's,
// copied. The others sample their own texel under the left light.
void EyeChunk::reuse_resample(std::size_t row, std::size_t nr, std::size_t& copied) {
    const Vec3f* __restrict lp = left->p.data();
    const float* __restrict llod = left->lod.data();
    const float* __restrict lrgb = left_rgb;
    float* __restrict lod_out = g.lod.data() + row * w;
    float* __restrict rgb_out = rgb + 3 * row * w;
    const std::uint32_t* __restrict rxs = sc.rx.data();
    const int* __restrict rpls = sc.rpl.data();
    const std::int32_t* __restrict rsrcs = sc.rsrc.data();
    const float* __restrict lods_r = sc.rlod.data();
    const float bias = o.lod_bias, tolerance = o.reuse_lod_tolerance;
    for (std::size_t k = 0; k < nr; ++k) {
        const std::uint32_t x = rxs[k];
        const std::size_t si = std::size_t(rsrcs[k]);
        const float lod = sampled_lod(lods_r[k], bias);
        lod_out[x] = lod;
        if (std::abs(llod[si] - lod) <= tolerance) {
            rgb_out[3 * x] = lrgb[3 * si], rgb_out[3 * x + 1] = lrgb[3 * si + 1];
            rgb_out[3 * x + 2] = lrgb[3 * si + 2];
            ++copied;
            continue;
        }
        // The texel at the left hit's point: D = (p - eye) / ((p - eye) . forward).
        const Vec3f& p = lp[si];
        const double tx = p.x - eye.position.x, ty = p.y - eye.position.y, tz = p.z - eye.position.z;
        const double inv = 1.0 / (tx * eye.forward.x + ty * eye.forward.y + tz * eye.forward.z);
        const double Dx = tx * inv, Dy = ty * inv, Dz = tz * inv;
        double u, v;
        float unused;
        maps[std::size_t(rpls[k])].map_lanes(1, &Dx, &Dy, &Dz, &u, &v, &unused);
        const std::size_t q = pending_count++;
        GS_CHECK(q < w);  // one pixel per column and row
        PendingPixel& pp = sc.pending[q];
        pp.x = x, pp.placement = rpls[k];
        sc.us[q] = u, sc.vs[q] = v, sc.lods[q] = lod;
        pp.scale = left->scale[si], pp.add = left->add[si];
    }
}

// sample: the row's pending painting pixels, runs of one painting in one call.
void EyeChunk::sample_pending() {
    const std::vector<PendingPixel>& pending = sc.pending;
    for (std::size_t k0 = 0; k0 < pending_count;) {
        const int pl = pending[k0].placement;
        std::size_t k1 = k0 + 1;
        while (k1 < pending_count && pending[k1].placement == pl) ++k1;
        SampleRequest r;
        r.painting = scene.paintings[std::size_t(pl)].painting;
        require(r.painting < paintings, "display: a painting of the scene is not in the virtual texture");
        r.u = sc.us.data() + k0, r.v = sc.vs.data() + k0, r.uv_stride = 1;
        r.lod = sc.lods.data() + k0;
        r.count = k1 - k0;
        r.filter = Filter::Trilinear;
        r.out = sc.texels.data() + 3 * k0;
        sample_serial_locked(vt, r);
        k0 = k1;
    }
}

// shade: the pending pixels' radiance in the Gallery's order of operations (its sRGB curve is
// exact, ours SrgbCurve's); on restrict locals (stores through rgb might otherwise alias the
// arrays' pointers).
void EyeChunk::shade_pending(std::size_t row) {
    const PendingPixel* __restrict pend = sc.pending.data();
    const float* __restrict tex = sc.texels.data();
    float* __restrict rgb_row = rgb + 3 * row * w;
    const float reflectance = o.painting_reflectance;
    const std::size_t count = pending_count;
    if (o.srgb_albedo) {
        for (std::size_t k = 0; k < count; ++k) {
            const PendingPixel& q = pend[k];
            const float* a = tex + 3 * k;
            const Vec3f albedo = Vec3f{srgb_decode(a[0]), srgb_decode(a[1]), srgb_decode(a[2])} * reflectance;
            const Vec3f L = albedo * q.scale + q.add;
            float* out = rgb_row + 3 * std::size_t(q.x);
            out[0] = L.x, out[1] = L.y, out[2] = L.z;
        }
    } else {
        for (std::size_t k = 0; k < count; ++k) {
            const PendingPixel& q = pend[k];
            const float* a = tex + 3 * k;
            const Vec3f albedo = Vec3f{a[0], a[1], a[2]} * (1.0f / 255.0f) * reflectance;
            const Vec3f L = albedo * q.scale + q.add;
            float* out = rgb_row + 3 * std::size_t(q.x);
            out[0] = L.x, out[1] = L.y, out[2] = L.z;
        }
    }
}

// Screen x of each column's centre, and past the last column (a short last packet's other
// lanes, which cast its last ray again: cast_rows' whole_tail) the last's.
std::vector<double> column_screen_x(const Camera& eye) {
    const std::uint32_t w = eye.width;
    std::vector<double> sx((std::size_t(w) + 15) / 16 * 16);
    for (std::uint32_t x = 0; x < w; ++x) sx[x] = eye.screen_x(x + 0.5);
    std::fill(sx.begin() + w, sx.end(), sx[w - 1]);
    return sx;
}

// Per column, its screen x less that of its packet's first column (PlaneMap::map_packet).
std::vector<float> column_offsets(const std::vector<double>& sx) {
    std::vector<float> ds(sx.size());
    for (std::size_t x = 0; x < sx.size(); ++x) ds[x] = float(sx[x] - sx[x & ~std::size_t(15)]);
    return ds;
}
}  // namespace

double DisplayPass::render_eye(const PaintingSceneView& scene, const DisplayLighting& lighting,
                               const VirtualTexture& vt, const Camera& eye, const DisplayOptions& o,
                               GBuffer& g, const Camera* claim_into, const float* left_rgb,
                               float* rgb, EyeStats& st, const RunRows* run) {
    const BakedLattice* const baked = lighting.baked_lattice();
    const auto t0 = Clock::now();
    std::vector<PlaneMap> maps;
    maps.reserve(scene.paintings.size());
    for (const PaintingPlacement& pp : scene.paintings) maps.emplace_back(pp, eye);
    const std::vector<double> column_sx = column_screen_x(eye);
    const std::vector<float> column_ds = column_offsets(column_sx);
    const GBuffer* left = reusing_ ? &g_[0] : nullptr;
    GS_CHECK(!left || left_rgb != nullptr);
    // One read lock for the frame: the workers' sampler calls run under it.
    const auto vt_lock = vt.read_lock();
    const EyeFrame frame{scene, lighting, vt, eye, o, g, rgb, eye.width,
                         claim_into != nullptr, hits_kept_, baked,
                         lanes16_for(baked),
                         claim_into ? std::optional<ClaimProjection>(std::in_place, *claim_into, claims_.data())
                                    : std::nullopt,
                         claim_into && rows_align(eye, *claim_into),
                         left, left_rgb, reusing_ ? sources_.data() : nullptr,
                         reusing_ ? claims_.data() : nullptr, 1.0f + o.edge_depth_ratio, maps.data(),
                         column_sx.data(), column_ds.data(), Vec3f(eye.position), srgb_curve(),
                         vt.layout().paintings.size(), frame_, next_serial()};
    EyeTotals totals;
    auto rows = [&](std::size_t rb, std::size_t re) {
        EyeChunk chunk(frame, rb, re);
        chunk.trace();
        chunk.add_to(totals);
    };
    // The left eye of a pair claims without compare-and-swaps inside its chunks' inner rows
    // (ClaimProjection::claim_rows): chunks as tall as the right eye's.
    const std::size_t chunk_rows =
        reusing_ || claim_into ? kReleaseChunkRows : rows_per_chunk(eye.height, o.threads);
    if (run)
        (*run)(chunk_rows, std::cref(rows));
    else
        parallel_for(eye.height, chunk_rows, rows, o.threads);
    if (left) {  // the chunks' first and last claim rows, left unclaimed for the next frame
        const std::uint32_t w = eye.width;
        for (std::size_t r0 = 0; r0 < eye.height; r0 += chunk_rows) {
            std::fill_n(claims_.data() + r0 * w, w, kUnclaimed);
            const std::size_t last = std::min<std::size_t>(eye.height, r0 + chunk_rows) - 1;
            std::fill_n(claims_.data() + last * w, w, kUnclaimed);
        }
        claims_clear_ = true;
        st.reused = totals.reused.load();
    }
    st.traced = totals.traced.load();
    st.hits = totals.hits.load();
    st.painting_pixels = totals.on_paintings.load();
    // In ticks until split_wall turns them into shares of the pass's wall time.
    st.rays_seconds = double(totals.rays_ticks.load());
    st.vt_seconds = double(totals.vt_ticks.load());
    st.shade_seconds = double(totals.shade_ticks.load());
    st.reuse_seconds = double(totals.reuse_ticks.load());  // the claims, or the edge release
    return seconds_since(t0);
}

}  // namespace gigascroll

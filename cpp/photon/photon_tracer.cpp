#include "photon/photon_tracer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <string>

#include "common/error.h"
#include "common/limits.h"
#include "common/parallel.h"
#include "photon/rng.h"

namespace gigascroll {

Vec3f sample_cosine(Vec3f n, float u1, float u2) {
    const float r = std::sqrt(u1);
    const float phi = 2.0f * float(M_PI) * u2;
    const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
    Vec3f t, b;
    basis(n, t, b);
    return t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z;
}

std::vector<Photon> trace_photons(const Scene& scene, std::uint64_t count, std::uint64_t seed,
                                  unsigned threads, TraceStats* stats, std::uint32_t pass,
                                  std::uint64_t max_stored) {
    std::vector<Photon> out;
    trace_photons(out, scene, count, seed, threads, stats, pass, max_stored);
    return out;
}

void trace_photons(std::vector<Photon>& out, const Scene& scene, std::uint64_t count, std::uint64_t seed,
                   unsigned threads, TraceStats* stats, std::uint32_t pass, std::uint64_t max_stored) {
    require(scene.committed(), "trace_photons: call Scene.commit() first");
    require(count > 0, "trace_photons: the photon count must be positive");
    require(count <= kMaxEmittedPhotons, "trace_photons: at most 2^32 photons per pass, got " +
                                             std::to_string(count) + " (progressive rendering takes more passes)");
    require_threads(threads, "trace_photons");
    require(pass < kMaxPasses, "trace_photons: pass out of range");
    const std::uint32_t stream = stream_id(StreamKind::Photon, pass);
    TraceStats st;
    st.emitted = count;
    st.emitted_power = scene.emitted_power();
    if (scene.emitter_count() == 0 || !scene.reflects_anything()) {
        out.clear();
        if (stats) *stats = st;
        return;  // nothing is ever stored
    }
    // Each photon carries W / N per unit of emitter weight; see Scene::sample_emitter.
    const double scale = double(scene.emitter_weight_total()) * M_PI / double(count);
    const float eps = scene.epsilon();

    // Stored photons of all threads, synchronised every kSync stores of one thread.
    std::atomic<std::uint64_t> stored_total{0};
    constexpr std::uint64_t kSync = 1024;
    auto over_budget = [&](std::uint64_t& unsynced) {
        const std::uint64_t total = stored_total.fetch_add(unsynced, std::memory_order_relaxed) + unsynced;
        unsynced = 0;
        if (total <= max_stored) return;
        throw InvalidArgument(
            "trace_photons: more than " + std::to_string(max_stored) + " photons stored (" +
            format_bytes(double(max_stored) * sizeof(Photon)) + ", the memory budget) from " +
            std::to_string(count) + " emitted: an albedo near 1 makes paths long (a closed room "
            "of albedo a stores a / (1 - a) photons per emitted photon); emit fewer photons");
    };

    // Chunks of 4096 photons, a small pass in up to 8 chunks of at least 256 so that it uses
    // both cores too (2^10 photons were one serial chunk). The chunking does not change the
    // photons: each one's random stream is its index's, and the chunks are concatenated in
    // photon order.
    const std::uint64_t kChunk = std::clamp<std::uint64_t>(count / 8, 256, 4096);
    const std::uint64_t chunks = (count + kChunk - 1) / kChunk;
    // Chunk c stores into its own slot of `out`, slot photons from c * slot (a closed room of
    // albedo ~0.6 stores ~1.5 photons per emitted one, so 2 per emitted one rarely overflow),
    // and past that into its spill vector. The slots are then closed up in place: no second
    // copy of the photons, and a reused `out` (a gallery relit) faults in no fresh pages,
    // which were a sixth of a 2^20-photon pass. Passes whose slots would pass 2^22 photons
    // (150 MiB, written in full) store into the spill vectors alone.
    const std::uint64_t slot = chunks * 2 * kChunk <= (std::uint64_t(1) << 22) ? 2 * kChunk : 0;
    out.resize(chunks * slot);
    std::vector<std::uint64_t> used(chunks, 0);
    std::vector<std::vector<Photon>> spill(chunks);
    parallel_for(chunks, 1, [&](std::size_t cb, std::size_t ce) {
        for (std::size_t c = cb; c < ce; ++c) {
            Photon* const mine = out.data() + c * slot;
            std::uint64_t n = 0;
            auto& part = spill[c];
            if (slot == 0) part.reserve(2 * kChunk);  // one allocation in the common case
            std::uint64_t unsynced = 0;
            const std::uint64_t end = std::min<std::uint64_t>(count, (c + 1) * kChunk);
            for (std::uint64_t i = c * kChunk; i < end; ++i) {
                Rng rng(seed, stream, i);
                const float ut = rng.uniform(), ua = rng.uniform(), ub = rng.uniform();
                const LightSample ls = scene.sample_emitter(ut, ua, ub);
                const float w = (ls.radiance.x + ls.radiance.y + ls.radiance.z) / 3.0f;
                Vec3f power = ls.radiance * float(scale / w);
                Vec3f o = ls.p + ls.n * eps;
                Vec3f d = sample_cosine(ls.n, rng.uniform(), rng.uniform());
                for (bool first = true;; first = false) {
                    Hit hit;
                    if (!scene.intersect(o, d, hit)) break;
                    if (!first) {
                        if (n < slot) mine[n++] = {hit.p, power, hit.n};
                        else part.push_back({hit.p, power, hit.n});
                        if (++unsynced == kSync) over_budget(unsynced);
                    }
                    const Vec3f albedo = scene.albedo_at(hit.tri, hit.p);
                    const float survive = max_component(albedo);
                    if (!(rng.uniform() < survive)) break;  // Russian roulette by albedo
                    power = power * (albedo / survive);
                    o = hit.p + hit.n * eps;
                    d = sample_cosine(hit.n, rng.uniform(), rng.uniform());
                }
            }
            used[c] = n;
            over_budget(unsynced);
        }
    }, threads);
    // Concatenated in photon order: slot c's photons, then its spill, for c = 0, 1, ...
    std::vector<std::size_t> start(chunks + 1, 0);
    bool spilled = false;
    for (std::size_t c = 0; c < chunks; ++c) {
        start[c + 1] = start[c] + used[c] + spill[c].size();
        spilled = spilled || !spill[c].empty();
    }
    if (!spilled) {
        // In place: each slot moves down to its start (start[c] <= c * slot), in order.
        for (std::size_t c = 1; c < chunks; ++c)
            if (used[c]) std::memmove(static_cast<void*>(out.data() + start[c]), out.data() + c * slot,
                                      used[c] * sizeof(Photon));
        out.resize(start[chunks]);
    } else {
        std::vector<Photon> merged(start[chunks]);
        parallel_for(chunks, 1, [&](std::size_t cb, std::size_t ce) {
            for (std::size_t c = cb; c < ce; ++c) {
                const auto at = merged.begin() + std::ptrdiff_t(start[c]);
                std::copy(out.begin() + std::ptrdiff_t(c * slot), out.begin() + std::ptrdiff_t(c * slot + used[c]), at);
                std::copy(spill[c].begin(), spill[c].end(), at + std::ptrdiff_t(used[c]));
                std::vector<Photon>().swap(spill[c]);
            }
        }, threads);
        out.swap(merged);
    }
    st.stored = out.size();
    if (stats) *stats = st;
}

}  // namespace gigascroll

// The photon hash grid of VR-photon-mapping §3.1. Cells have edge r (the gather radius); the origin is
// just below the smallest photon and one empty layer pads each side. A photon's cell (x, y, z)
// has the linear hash z*gx*gy + y*gx + x (eq. 2); photons are counting-sorted by hash and
// start[h] is the prefix sum, so the photons of cells x-1..x+1 of one row are one contiguous
// run and a query visits the 3x3x3 neighbourhood as 9 runs.
//
// When gx*gy*gz cells would not fit (a tiny radius in a large scene) the grid falls back to a
// hashed table of about twice the photon count (as pbrt-v4's SPPM does): cells map to buckets
// by a spatial hash, and a query visits the distinct buckets of its 27 cells.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/parallel.h"
#include "photon/photon_tracer.h"

namespace gigascroll {

// A contiguous range of photons [begin, end) in a map's storage order.
struct PhotonRun {
    std::uint64_t begin, end;
};

// A stable counting sort of indices 0..n-1 by key (every key < keys): start[k] the exclusive
// prefix sum of the counts (keys + 1 entries), and place(i, j) called once per i with its
// sorted position j. threads > 1 (0: all cores) sorts on several threads when the keys are
// few beside the indices (a count table per thread): each thread's indices go after the
// earlier threads' within every key, so the positions are the serial sort's, whatever the
// thread count.
template <class Index, class Place>
void counting_sort(const std::vector<std::uint64_t>& key, std::uint64_t keys, std::vector<Index>& start,
                   unsigned threads, Place&& place) {
    const std::size_t n = key.size();
    const unsigned parts = threads == 0 ? default_threads() : threads;
    start.assign(keys + 1, 0);
    if (parts < 2 || n < (std::size_t(1) << 16) || keys > n / 8) {
        for (std::uint64_t k : key) ++start[k + 1];
        for (std::uint64_t i = 0; i < keys; ++i) start[i + 1] += start[i];
        std::vector<Index> fill(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < n; ++i) place(i, fill[key[i]]++);
        return;
    }
    // Part p (indices [p n / parts, (p + 1) n / parts)) counts its keys, then fills key k from
    // start[k] plus the earlier parts' counts of k.
    std::vector<std::vector<Index>> fill(parts);
    auto part = [&](std::size_t p) { return std::pair{p * n / parts, (p + 1) * n / parts}; };
    parallel_for(parts, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
            fill[p].assign(keys, 0);
            const auto [i0, i1] = part(p);
            for (std::size_t i = i0; i < i1; ++i) ++fill[p][key[i]];
        }
    }, parts);
    Index running = 0;
    for (std::uint64_t k = 0; k < keys; ++k) {
        start[k] = running;
        for (unsigned p = 0; p < parts; ++p) {
            const Index c = fill[p][k];
            fill[p][k] = running;
            running += c;
        }
    }
    start[keys] = running;
    parallel_for(parts, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
            const auto [i0, i1] = part(p);
            Index* f = fill[p].data();
            for (std::size_t i = i0; i < i1; ++i) place(i, f[key[i]]++);
        }
    }, parts);
}

// The structure-of-arrays grids' storage: `photons` counting-sorted by key (every key < keys)
// into `sorted`, start[k] the exclusive prefix sum of the counts (keys + 1 entries), and the
// sorted photons' position, normal and power components in `lanes` (px, py, pz, nx, ny, nz,
// pr, pg, pb). One routine, so both grids store photons in the same order; threads as in
// counting_sort (the same order on any number).
template <class Index>
void sort_photons_by_key(const std::vector<Photon>& photons, const std::vector<std::uint64_t>& key,
                         std::uint64_t keys, std::vector<Index>& start, std::vector<Photon>& sorted,
                         const std::array<std::vector<float>*, 9>& lanes, unsigned threads = 1) {
    const std::size_t n = photons.size();
    sorted.resize(n);
    Photon* out = sorted.data();
    counting_sort(key, keys, start, threads, [&](std::size_t i, Index j) { out[j] = photons[i]; });
    for (auto* v : lanes) v->resize(n);
    auto& [px, py, pz, nx, ny, nz, pr, pg, pb] = lanes;
    parallel_for(n, std::size_t(1) << 15, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const Photon& p = out[i];
            (*px)[i] = p.p.x, (*py)[i] = p.p.y, (*pz)[i] = p.p.z;
            (*nx)[i] = p.n.x, (*ny)[i] = p.n.y, (*nz)[i] = p.n.z;
            (*pr)[i] = p.power.x, (*pg)[i] = p.power.y, (*pb)[i] = p.power.z;
        }
    }, threads == 0 ? default_threads() : threads);
}

// Sum over the runs of weight(j) * power_j, the weights' sum into *count (if not null). The
// structure-of-arrays grids share it: kLanes independent partial sums make a fixed-width
// inner loop that vectorises, and one summation order keeps their results bit-identical.
template <class Weight>
inline Vec3f sum_runs(const PhotonRun* rs, int nr, const float* pr, const float* pg,
                      const float* pb, Weight&& weight, float* count) {
    constexpr int kLanes = 8;
    float sr[kLanes] = {}, sg[kLanes] = {}, sb[kLanes] = {}, sw[kLanes] = {};
    for (int i = 0; i < nr; ++i) {
        std::uint64_t j = rs[i].begin;
        for (; j + kLanes <= rs[i].end; j += kLanes)
            for (int l = 0; l < kLanes; ++l) {
                const float w = weight(j + l);
                sr[l] += w * pr[j + l];
                sg[l] += w * pg[j + l];
                sb[l] += w * pb[j + l];
                sw[l] += w;
            }
        for (int l = 0; j < rs[i].end; ++j, ++l) {
            const float w = weight(j);
            sr[l] += w * pr[j];
            sg[l] += w * pg[j];
            sb[l] += w * pb[j];
            sw[l] += w;
        }
    }
    Vec3f total{0, 0, 0};
    float found = 0;
    for (int l = 0; l < kLanes; ++l) {
        total += Vec3f(sr[l], sg[l], sb[l]);
        found += sw[l];
    }
    if (count) *count = found;
    return total;
}

class HashGrid {
public:
    enum class Mode { Auto, Dense, Hashed };

    // Copies the photons in cell order. Auto uses the dense grid when its cell count is at
    // most max(2^22, 4 * photons), else the hashed table.
    HashGrid(const std::vector<Photon>& photons, float radius, Mode mode = Mode::Auto);

    bool dense() const { return dense_; }
    float radius() const { return r_; }
    std::size_t size() const { return photons_.size(); }
    const std::vector<Photon>& photons() const { return photons_; }
    std::uint64_t cell_count() const { return dense_ ? cells_ : buckets_; }

    // The runs holding every photon within radius() of q (and others: callers test the
    // distance). Writes at most 27 runs; returns how many.
    int runs(Vec3f q, PhotonRun out[27]) const;

    // Calls f(photon, d2) for each photon with squared distance d2 <= r2. f may shrink r2
    // (k-nearest search does). r2 must start at most radius()^2.
    template <typename F>
    void for_each_in_radius(Vec3f q, float& r2, F&& f) const {
        PhotonRun rs[27];
        const int n = runs(q, rs);
        for (int i = 0; i < n; ++i)
            for (std::uint64_t j = rs[i].begin; j < rs[i].end; ++j) {
                const Photon& p = photons_[j];
                const Vec3f d = p.p - q;
                const float d2 = dot(d, d);
                if (d2 <= r2) f(p, d2);
            }
    }

    // Heap-free box gather: the summed power of the photons within sqrt(r2) <= radius() of q
    // whose normals agree with n (gather.h), over structure-of-arrays copies so the loop over
    // each run vectorises. *count (if given) receives how many photons were summed.
    Vec3f sum_box(Vec3f q, Vec3f n, float r2, float* count = nullptr) const;

    // The cell holding q (clamped to one cell outside the grid); true when inside the grid.
    bool cell_of(Vec3f q, std::int64_t c[3]) const;
    // A sort key ordering cells as the dense hash does (z, then y, then x).
    std::uint64_t cell_order(const std::int64_t c[3]) const {
        return (std::uint64_t(c[2] + 2) * std::uint64_t(g_[1] + 4) + std::uint64_t(c[1] + 2)) *
                   std::uint64_t(g_[0] + 4) + std::uint64_t(c[0] + 2);
    }

private:
    std::uint64_t bucket(std::int64_t x, std::int64_t y, std::int64_t z) const;

    float r_ = 0, inv_r_ = 0;
    bool dense_ = true;
    Vec3f origin_;
    std::int64_t g_[3] = {0, 0, 0};
    std::uint64_t cells_ = 0, buckets_ = 0;
    std::vector<std::uint64_t> start_;  // prefix sums, one more entry than cells/buckets
    std::vector<Photon> photons_;
    // photons_ again as structure of arrays (position, normal, power), for sum_box.
    std::vector<float> px_, py_, pz_, nx_, ny_, nz_, pr_, pg_, pb_;
};

}  // namespace gigascroll

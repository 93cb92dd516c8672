// Arrays across the binding: handing C++ memory to numpy without a copy (the two ways the
// bindings do it), uint64 key buffers in, and tile keys in their two forms.
// In both, a capsule owns the memory from the moment it exists, so an exception while C++
// fills it (with the GIL released) frees it instead of leaking.
#pragma once
#include <nanobind/ndarray.h>

#include <cstddef>
#include <initializer_list>
#include <utility>
#include <string>
#include <tuple>
#include <vector>

#include "common/error.h"
#include "pack/tile_key.h"
#include "views/request_processing.h"

namespace gigascroll::bindings {

// An uninitialised C-contiguous numpy array of the given shape for C++ to fill (tiles,
// painting rows, the frame loop's buffers: zeroing memory that is overwritten anyway is
// measurable at several MB a frame). Extra: nanobind ndarray annotations (nb::ndim<3>, ...).
template <typename T, typename... Extra>
struct FreshArray {
    explicit FreshArray(std::initializer_list<std::size_t> shape) {
        std::size_t n = 1;
        for (std::size_t s : shape) n *= s;
        data = new T[n];
        nanobind::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
        array = nanobind::ndarray<nanobind::numpy, T, Extra...>(data, shape.size(), shape.begin(),
                                                                owner);
    }
    T* data;
    nanobind::ndarray<nanobind::numpy, T, Extra...> array;
};

// Moves a vector into a numpy array of the given shape (default: 1-D, its size).
template <typename T>
nanobind::ndarray<nanobind::numpy, T> to_numpy(std::vector<T>&& v,
                                               std::initializer_list<std::size_t> shape = {}) {
    auto* heap = new std::vector<T>(std::move(v));
    nanobind::capsule owner(heap,
                            [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
    const std::size_t size = heap->size();
    if (shape.size() == 0)
        return nanobind::ndarray<nanobind::numpy, T>(heap->data(), 1, &size, owner);
    return nanobind::ndarray<nanobind::numpy, T>(heap->data(), shape.size(), shape.begin(), owner);
}

// A uint64 array of any shape, viewed as a flat feedback buffer (nanobind makes a C-contiguous
// copy of a strided one). Other dtypes are refused rather than converted: a key is not a
// number to round.
using KeyArray = nanobind::ndarray<const std::uint64_t, nanobind::c_contig, nanobind::device::cpu>;
struct HeldBuffer {
    KeyArray array;
    FeedbackBuffer view;
};

inline HeldBuffer as_buffer(nanobind::handle h, const char* what) {
    nanobind::ndarray<> probe;
    if (!nanobind::try_cast(h, probe))
        throw gigascroll::InvalidArgument(std::string(what) + " must be a numpy array of uint64 request keys");
    require(probe.dtype() == nanobind::dtype<std::uint64_t>(),
            std::string(what) + " must have dtype uint64 (request keys)");
    KeyArray a;
    if (!nanobind::try_cast(h, a))
        throw gigascroll::InvalidArgument(std::string(what) + " must be a CPU array");
    return {a, FeedbackBuffer(a.data(), a.size())};
}

// Accepts one array or a sequence of arrays (left eye, right eye, magnifier ...).
inline std::vector<HeldBuffer> as_buffers(nanobind::handle h) {
    std::vector<HeldBuffer> out;
    nanobind::ndarray<> probe;
    if (nanobind::try_cast(h, probe)) {
        out.push_back(as_buffer(h, "feedback buffer"));
        return out;
    }
    if (!nanobind::isinstance<nanobind::sequence>(h))
        throw gigascroll::InvalidArgument("feedback buffers must be a uint64 array or a list of them");
    for (nanobind::handle item : nanobind::borrow<nanobind::sequence>(h))
        out.push_back(as_buffer(item, "feedback buffer"));
    return out;
}

inline std::vector<FeedbackBuffer> views_of(const std::vector<HeldBuffer>& held) {
    std::vector<FeedbackBuffer> v;
    for (const auto& b : held) v.push_back(b.view);
    return v;
}


// Tile keys cross as (painting, level, tx, ty) tuples or as uint64 request keys.
using KeyTuple = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;
inline TileKey to_key(const KeyTuple& k) {
    return {std::get<0>(k), std::get<1>(k), std::get<2>(k), std::get<3>(k)};
}
inline KeyTuple to_tuple(const TileKey& k) { return {k.painting, k.level, k.tx, k.ty}; }

using RequestKeys = nanobind::ndarray<const std::uint64_t, nanobind::ndim<1>, nanobind::c_contig,
                                      nanobind::device::cpu>;
// Request keys (pack_request layout) as tile keys; the loader and the cache check ranges.
inline std::vector<TileKey> to_tile_keys(const RequestKeys& a) {
    std::vector<TileKey> keys(a.shape(0));
    for (std::size_t i = 0; i < keys.size(); ++i) keys[i] = unpack_request(a.data()[i]);
    return keys;
}

// (n, 4) integer keys (painting, level, tx, ty), each in [0, 2^20).
using Keys = nanobind::ndarray<const std::int64_t, nanobind::ndim<2>, nanobind::c_contig,
                               nanobind::device::cpu>;
inline std::vector<TileKey> to_keys(const Keys& a) {
    require(a.shape(1) == 4, "keys must have shape (n, 4): painting, level, tx, ty");
    std::vector<TileKey> keys(a.shape(0));
    const std::int64_t* d = a.data();
    for (std::size_t i = 0; i < keys.size(); ++i) {
        for (int c = 0; c < 4; ++c)
            require(d[4 * i + c] >= 0 && d[4 * i + c] < (1 << 20), "key values must be in [0, 2^20)");
        keys[i] = {std::uint32_t(d[4 * i]), std::uint32_t(d[4 * i + 1]), std::uint32_t(d[4 * i + 2]),
                   std::uint32_t(d[4 * i + 3])};
    }
    return keys;
}

inline std::uint32_t checked_u32(std::int64_t v, std::int64_t hi, const char* what) {
    require(v >= 0 && v <= hi, std::string(what) + " out of range");
    return static_cast<std::uint32_t>(v);
}

}  // namespace gigascroll::bindings

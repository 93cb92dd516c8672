// Handing C++ memory to numpy without a copy: one place for the two ways the bindings do it.
// In both, a capsule owns the memory from the moment it exists, so an exception while C++
// fills it (with the GIL released) frees it instead of leaking.
#pragma once
#include <nanobind/ndarray.h>

#include <cstddef>
#include <initializer_list>
#include <utility>
#include <vector>

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

}  // namespace gigascroll::bindings

// One registration function per folder of the core, called in the order data flows; the
// bindings only forward (argument conversion, the GIL, numpy arrays), the logic is the core's.
#pragma once
#include <nanobind/nanobind.h>

namespace gigascroll::bindings {
// f() run without the GIL (a call that may wait on the core, e.g. for another thread's
// frame), its result returned once the GIL is held again.
template <typename F>
auto without_gil(F&& f) {
    nanobind::gil_scoped_release release;
    return f();
}

void bind_common(nanobind::module_& m);    // errors, threads
void bind_pack(nanobind::module_& m);      // tile pack reader and builder, geometry, tile keys
void bind_views(nanobind::module_& m);     // cameras, exhibition scene, feedback, request processing
void bind_loading(nanobind::module_& m);   // tile loader, loading strategies
void bind_cache(nanobind::module_& m);     // physical cache and page table, lookup, drain
void bind_sampling(nanobind::module_& m);  // VT sampling, mip texture, sparse display
void bind_display(nanobind::module_& m);   // the full-resolution display pass
void bind_photon(nanobind::module_& m);    // photon scene, photon maps, renderer
void bind_gallery(nanobind::module_& m);   // the gallery: room, paintings, lighting, display
}  // namespace gigascroll::bindings

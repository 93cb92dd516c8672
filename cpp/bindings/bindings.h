// One registration function per subsystem; module.cpp calls them in order.
#pragma once
#include <nanobind/nanobind.h>

namespace gigascroll::bindings {
void bind_common(nanobind::module_& m);
void bind_pack(nanobind::module_& m);     // vt: tile pack, pack builder, layout
void bind_runtime(nanobind::module_& m);  // concurrency + vt: loader, cache, page table, sampler
void bind_views(nanobind::module_& m);    // vt: exhibition scene, views, feedback, request processing
void bind_photon(nanobind::module_& m);   // photon: scene, cameras, photon maps, renderer
}  // namespace gigascroll::bindings

#include "bindings/bindings.h"

namespace nb = nanobind;

namespace gigascroll::bindings {
void bind_views(nb::module_& m) { (void)m; }
}  // namespace gigascroll::bindings

#include "bindings/bindings.h"

namespace nb = nanobind;

namespace gigascroll::bindings {
void bind_runtime(nb::module_& m) { (void)m; }
}  // namespace gigascroll::bindings

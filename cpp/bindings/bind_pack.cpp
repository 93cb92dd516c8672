#include "bindings/bindings.h"

namespace nb = nanobind;

namespace gigascroll::bindings {
void bind_pack(nb::module_& m) { (void)m; }
}  // namespace gigascroll::bindings

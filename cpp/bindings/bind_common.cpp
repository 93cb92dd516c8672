#include <thread>

#include "bindings/bindings.h"
#include "common/error.h"

namespace nb = nanobind;

namespace gigascroll::bindings {
void bind_common(nb::module_& m) {
    // Core errors reach Python as ValueError (bad arguments) or IOError (files).
    nb::register_exception_translator([](const std::exception_ptr& p, void*) {
        try {
            std::rethrow_exception(p);
        } catch (const gigascroll::IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const gigascroll::InvalidArgument& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });
    m.def("hardware_threads", [] { return std::thread::hardware_concurrency(); },
          "Number of hardware threads the core will use by default.");
}
}  // namespace gigascroll::bindings

#include "amb_fast/errors.hpp"
#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
    m.doc() = "amb_fast compiled core: the sampled-data AMB loop (see python/amb_fast for the API)";
    bind_params(m);
    bind_loop(m);
    bind_spectrum(m);
    bind_sweep(m);
    bind_mimo(m);
    bind_nd_loop(m);
    bind_campbell(m);

    // Touchdown is an event with a time and a place: amb_fast.TouchdownError carries both.
    py::register_exception_translator([](std::exception_ptr error) {
        try {
            if (error) std::rethrow_exception(error);
        } catch (const amb_fast::Touchdown& touchdown) {
            const py::object cls = py::module_::import("amb_fast._errors").attr("TouchdownError");
            const py::object value = cls(touchdown.what(), touchdown.time, touchdown.position);
            PyErr_SetObject(cls.ptr(), value.ptr());
        }
    });
}

#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
    m.doc() = "amb_fast compiled core: the sampled-data AMB loop (see python/amb_fast for the API)";
    bind_params(m);
    bind_loop(m);
    bind_spectrum(m);
    bind_sweep(m);
}

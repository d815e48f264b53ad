// The one include for every binding file.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace py = pybind11;

void bind_params(py::module_& m);
void bind_loop(py::module_& m);
void bind_spectrum(py::module_& m);
void bind_sweep(py::module_& m);

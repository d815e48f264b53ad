// The one include for every binding file.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "amb_fast/interrupt.hpp"

namespace py = pybind11;

// Runs f with the GIL released and stoppable by Ctrl-C: the calling thread looks at Python's signals
// every 50 ms between blocks (PyErr_CheckSignals, with the GIL taken for that moment), every computing
// thread at what it found. A stopped call raises KeyboardInterrupt (or the signal handler's error).
template <class F>
auto interruptible(F&& f) {
    std::atomic<bool> signalled{false};
    const auto caller = std::this_thread::get_id();
    auto last = std::chrono::steady_clock::now();
    const amb_fast::InterruptCheck check = [&]() -> bool {
        if (signalled.load(std::memory_order_relaxed)) return true;
        if (std::this_thread::get_id() != caller) return false;
        const auto now = std::chrono::steady_clock::now();
        if (now - last < std::chrono::milliseconds(50)) return false;
        last = now;
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() == 0) return false;
        signalled = true;
        return true;
    };
    try {
        py::gil_scoped_release release;
        const amb_fast::ScopedInterruptCheck installed(&check);
        return f();
    } catch (const amb_fast::Interrupted&) {
        throw py::error_already_set();  // the error PyErr_CheckSignals set
    }
}

void bind_params(py::module_& m);
void bind_loop(py::module_& m);
void bind_spectrum(py::module_& m);
void bind_sweep(py::module_& m);
void bind_mimo(py::module_& m);
void bind_nd_loop(py::module_& m);
void bind_campbell(py::module_& m);

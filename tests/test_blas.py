"""amb_fast's small-matrix-heavy functions run BLAS on one thread, and give the process its setting back."""

from __future__ import annotations

import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

import amb_fast as af  # noqa: E402
from amb_fast._blas import one_blas_thread  # noqa: E402


def blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpoolctl.threadpool_info() if lib["user_api"] == "blas"]


def test_one_blas_thread_inside_and_the_setting_restored() -> None:
    before = blas_threads()
    if not before:
        pytest.skip("no BLAS library that threadpoolctl can see")
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        outside = blas_threads()
        inside = one_blas_thread(blas_threads)()
        assert inside == [1] * len(outside)
        assert blas_threads() == outside
    assert blas_threads() == before


def test_the_calibration_entry_points_are_wrapped() -> None:
    from amb_fast import RigFit, design_controller, fit_rig

    for function in (fit_rig, design_controller, RigFit.predict, RigFit.coefficients, af.sweep, af.two_axis.sweep):
        layers = []
        while function is not None:
            layers.append(getattr(function, "one_blas_thread", False))
            function = getattr(function, "__wrapped__", None)
        assert any(layers)

"""amb_fast's small-matrix-heavy functions run BLAS on one thread, and give the process its setting back."""

from __future__ import annotations

from dataclasses import replace

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
    from amb_fast._linear_poles import _affine_closed_loop

    entry_points = (
        fit_rig,
        design_controller,
        RigFit.predict,
        RigFit.coefficients,
        _affine_closed_loop,
    )
    for function in entry_points:
        layers = []
        while function is not None:
            layers.append(getattr(function, "one_blas_thread", False))
            function = getattr(function, "__wrapped__", None)
        assert any(layers)


def test_a_sweep_makes_its_points_with_blas_on_one_thread() -> None:
    """Where a sweep makes each point's rig and controller (a factory, a Controller's parameters, Rig
    fields), on this thread or an executor's, BLAS runs on one thread; every sweep here (PID gains too)
    enters the guard that also stops OpenBLAS's idle workers (tests/test_blas_parked.py)."""
    import concurrent.futures

    from amb_fast import _sweep

    if not blas_threads():
        pytest.skip("no BLAS library that threadpoolctl can see")
    rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=10.0, f_max=100.0)
    seen: list[list[int]] = []

    def factory(kp: float):  # noqa: ANN202
        seen.append(blas_threads())
        return rig, replace(pid, kp=kp)

    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        outside = blas_threads()
        af.sweep(factory, sphs, kp=[2000.0, 2500.0], progress=False)
        with concurrent.futures.ThreadPoolExecutor(2) as pool:
            af.sweep(factory, sphs, kp=[2000.0, 2500.0], executor=pool, progress=False)
        assert seen == [[1] * len(outside)] * 4
        assert blas_threads() == outside

    entered = []
    original = _sweep.blas_parked

    def counted():  # noqa: ANN202
        entered.append(1)
        return original()

    _sweep.blas_parked = counted
    try:
        af.sweep(rig, pid, sphs, kp=[2000.0, 2500.0], ki=[0.0, 100.0], progress=False)
        assert entered == [1]
        af.sweep(rig, pid, sphs, amp_bandwidth=[900.0, 1100.0], progress=False)
        assert entered == [1, 1]
    finally:
        _sweep.blas_parked = original


def test_a_guard_inside_a_guard_does_nothing() -> None:
    """A sweep's points each miss a cache whose function guards BLAS: inside the sweep's own guard those
    enter no second threadpoolctl limit, and leaving them keeps BLAS on one thread."""
    from amb_fast import _blas

    if not blas_threads():
        pytest.skip("no BLAS library that threadpoolctl can see")
    with _blas.blas_on_one_thread():
        controller = _blas._controller
        limits = []
        original = controller.limit
        controller.limit = lambda **kwargs: limits.append(kwargs) or original(**kwargs)
        try:
            with _blas.blas_on_one_thread():
                assert blas_threads() == [1] * len(blas_threads())
            assert blas_threads() == [1] * len(blas_threads())
            assert limits == []
        finally:
            del controller.limit
    with _blas.blas_on_one_thread():  # a fresh guard after the first ended
        assert blas_threads() == [1] * len(blas_threads())


def _threads_in_chunk(values: dict, seeds, core_threads: int) -> dict:
    import numpy as np

    return {"threads": np.full(seeds.size, max(blas_threads() or [1]))}


@pytest.mark.parametrize("here", [True, False])
def test_the_sweep_driver_runs_its_chunks_on_one_blas_thread(here: bool) -> None:
    """Every sweep (one axis, two axes, rotors) runs through ``run_points``: its chunks see one BLAS thread."""
    import numpy as np

    from amb_fast._sweep import run_points

    if not blas_threads():
        pytest.skip("no BLAS library that threadpoolctl can see")
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        out = run_points(_threads_in_chunk, (), {"kp": np.arange(4.0)}, np.arange(4), workers=2, executor=None,
                         progress=False, bytes_per_point=8, here=here)  # fmt: skip
        assert blas_threads() == [2] * len(blas_threads())
    assert out["threads"].tolist() == [1, 1, 1, 1]

"""A sweep scales whatever numpy work the process did before it (issue 25, case 11).

After a multi-threaded OpenBLAS call (``a @ a`` of 300x300) OpenBLAS's idle workers busy-wait for about
0.1 s, whatever thread count is set, and take a core from the sweep's second thread. These tests check
the mechanism without timing anything: during the sweep's core call no OpenBLAS worker thread exists
and BLAS is on one thread; afterwards the user's thread counts are back and the pools start again on
the next call. Linux only (threads are listed from /proc).
"""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

import amb_fast as af  # noqa: E402
from amb_fast import _blas, _sweep  # noqa: E402

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="threads listed from /proc")


def openblas_pools() -> list[dict]:
    return [
        lib
        for lib in threadpoolctl.threadpool_info()
        if lib["internal_api"] == "openblas" and lib.get("threading_layer") == "pthreads"
    ]


def blas_threads() -> list[int]:
    return [lib["num_threads"] for lib in threadpoolctl.threadpool_info() if lib["user_api"] == "blas"]


def native_threads() -> set[int]:
    """Threads of the process that Python did not start (OpenBLAS's workers, here)."""
    python = {t.native_id for t in threading.enumerate()}
    return {int(tid) for tid in os.listdir("/proc/self/task")} - python


@pytest.fixture
def seen_in_core(monkeypatch: pytest.MonkeyPatch) -> list[tuple[set[int], list[int]]]:
    """What the sweep's core call sees: the native threads and the BLAS thread counts."""
    seen: list[tuple[set[int], list[int]]] = []
    core = _sweep._core

    class Recording:
        def __getattr__(self, name: str):  # noqa: ANN204
            return getattr(core, name)

        def run_sweep(self, *args, **kwargs):  # noqa: ANN202
            seen.append((native_threads(), blas_threads()))
            return core.run_sweep(*args, **kwargs)

    monkeypatch.setattr(_sweep, "_core", Recording())
    # The workers spin for ~0.1 s after a@a; on a loaded machine this test may reach the sweep later: the
    # check of a running native thread is made true here (tested on its own below).
    monkeypatch.setattr(_blas, "_native_thread_running", lambda: True)
    return seen


def test_running_native_threads_are_seen() -> None:
    """A native thread busy in C (here: the core's threads inside a long eigenvalue call started from a
    Python thread) is seen as running; with none, nothing is."""
    from amb_fast import _core

    assert isinstance(_blas._native_thread_running(), bool)
    stack = np.random.default_rng(0).random((40_000, 12, 12))
    seen: list[bool] = []
    done = threading.Event()

    def busy() -> None:
        _core.eigenvalues(stack, 2)
        done.set()

    worker = threading.Thread(target=busy)
    worker.start()
    while not done.is_set():
        seen.append(_blas._native_thread_running())
    worker.join()
    assert any(seen)


def user_matmul() -> set[int]:
    """The user's 300x300 ``a @ a`` (multi-threaded: OpenBLAS's workers take part, then spin); returns
    those workers: the native threads it started (other libraries' pools, an OpenMP runtime's that an
    earlier test loaded, are not OpenBLAS's)."""
    for stop in _blas._pool_stoppers():
        stop()
    others = native_threads()
    a = np.random.default_rng(0).random((300, 300))
    a @ a
    workers = native_threads() - others
    assert workers, "OpenBLAS's workers exist after a multi-threaded call"
    return workers


def test_no_openblas_worker_during_the_core_call_and_the_settings_back(seen_in_core) -> None:
    if not openblas_pools():
        pytest.skip("no OpenBLAS built on pthreads in this process")
    rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=10.0, f_max=200.0)
    before = blas_threads()
    for user_limit in (2, 3):
        with threadpoolctl.threadpool_limits(user_limit, user_api="blas"):
            user = blas_threads()
            workers = user_matmul()
            assert workers, "OpenBLAS's workers exist after a multi-threaded call"
            af.sweep(rig, pid, sphs, kp=np.linspace(1800.0, 3000.0, 40), workers=2, progress=False)
            inside, counts = seen_in_core[-1]
            others = [(t.name, t.daemon) for t in threading.enumerate()]
            assert inside & workers == set(), others  # before the fix: the workers, spinning
            assert counts == [1] * len(user)
            assert blas_threads() == user  # the user's setting restored
            # the user's numpy after the sweep: right, on its pools again
            a = np.random.default_rng(1).random((300, 300))
            np.testing.assert_allclose(a @ a, np.einsum("ij,jk->ik", a, a), rtol=1e-12, atol=1e-12)
            assert native_threads()
    assert blas_threads() == before


def test_a_sweep_on_rig_fields_and_a_single_thread_user_setting(seen_in_core) -> None:
    if not openblas_pools():
        pytest.skip("no OpenBLAS built on pthreads in this process")
    rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=10.0, f_max=100.0)
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        workers = user_matmul()
        af.sweep(rig, pid, sphs, amp_bandwidth=[900.0, 1100.0], workers=2, progress=False)
    assert seen_in_core[-1][0] & workers == set()
    with threadpoolctl.threadpool_limits(1, user_api="blas"):
        af.sweep(rig, pid, sphs, kp=[2000.0, 2500.0], workers=2, progress=False)
        assert blas_threads() == [1] * len(blas_threads())


def test_pools_are_left_alone_while_another_thread_may_use_blas(seen_in_core) -> None:
    """Stopping a pool under another thread's call could hang it: with a non-daemon thread alive the
    workers stay (BLAS is still on one thread)."""
    if not openblas_pools():
        pytest.skip("no OpenBLAS built on pthreads in this process")
    release = threading.Event()
    other = threading.Thread(target=release.wait)
    other.start()
    limits = threadpoolctl.threadpool_limits(2, user_api="blas")
    try:
        workers = user_matmul()
        rig, pid, sphs = af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=10.0, f_max=100.0)
        af.sweep(rig, pid, sphs, kp=[2000.0, 2500.0], workers=2, progress=False)
        inside, counts = seen_in_core[-1]
        assert workers and workers <= inside  # the workers still there
        assert counts == [1] * len(counts)
    finally:
        limits.restore_original_limits()
        release.set()
        other.join()


def test_guards_overlapping_on_two_threads_restore_the_users_setting() -> None:
    """Thread A enters, thread B enters, A leaves, B leaves: the process ends where it began (before, B
    took A's limit of one thread for the user's setting and left the process on one thread)."""
    if not blas_threads():
        pytest.skip("no BLAS library that threadpoolctl can see")
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
    inside: dict[str, list[int]] = {}

    def thread_a() -> None:
        with _blas.blas_on_one_thread():
            a_in.set()
            b_in.wait()
            inside["a"] = blas_threads()
        a_out.set()

    def thread_b() -> None:
        a_in.wait()
        with _blas.blas_on_one_thread():
            b_in.set()
            a_out.wait()
            inside["b"] = blas_threads()  # A has left: still one thread while B is inside

    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        user = blas_threads()
        threads = [threading.Thread(target=thread_a), threading.Thread(target=thread_b)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert inside == {"a": [1] * len(user), "b": [1] * len(user)}
        assert blas_threads() == user


def test_two_axis_and_rotor_sweeps_park_the_pools_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """Siblings: the two-axis sweep's core call and the rotor sweep's points (on threads) run with BLAS
    on one thread and no OpenBLAS worker thread."""
    if not openblas_pools():
        pytest.skip("no OpenBLAS built on pthreads in this process")
    monkeypatch.setattr(_blas, "_native_thread_running", lambda: True)  # (as in seen_in_core)
    from amb_fast.system import _sweep as rotor_sweep
    from amb_fast.system import _sweep as two_axis_sweep  # one sweep module for every N

    seen: list[tuple[set[int], list[int]]] = []
    core = two_axis_sweep._core

    class Recording:
        def __getattr__(self, name: str):  # noqa: ANN204
            return getattr(core, name)

        def mimo_line_sweep(self, *args, **kwargs):  # noqa: ANN202
            seen.append((native_threads(), blas_threads()))
            return core.mimo_line_sweep(*args, **kwargs)

    monkeypatch.setattr(two_axis_sweep, "_core", Recording())
    run = rotor_sweep.run_experiment

    def recorded(*args, **kwargs):  # noqa: ANN202
        seen.append((native_threads(), blas_threads()))
        return run(*args, **kwargs)

    monkeypatch.setattr(rotor_sweep, "run_experiment", recorded)
    workers: set[int] = set()
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        user = blas_threads()
        workers |= user_matmul()
        af.two_axis.sweep(af.TwoAxisRig.paper(), af.PID.paper(), af.schroeder_multisine(f0=0.25, f_max=50.0),
                          kp=[2000.0, 2500.0], progress=False)  # fmt: skip
        assert seen and blas_threads() == user
        workers |= user_matmul()
        rig = af.RotorRig.example()
        sphs = af.schroeder_multisine(f0=20.0, f_max=400.0)  # 200-sample periods: quick
        # one point at a time: a point's core threads are native threads the next point would see
        af.sweep(rig, af.RotorRig.example_controller(), sphs, speed=[0.0, 100.0], periods=3, workers=1,
                 progress=False)  # fmt: skip
        assert len(seen) >= 3 and blas_threads() == user
    assert workers
    for inside, counts in seen:
        assert inside & workers == set()
        assert counts == [1] * len(user)


def test_the_campbell_diagram_and_the_run_up_park_the_pools_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """Siblings: the Campbell diagram and the unbalance run-up run their speeds on the core's threads too; right
    after the user's multi-threaded numpy call OpenBLAS's spinning workers took a core from them (a 500-speed
    Campbell diagram: 40 ms, 57-79 ms after the call). Their core call sees no OpenBLAS worker and one BLAS
    thread, and the user's setting is back afterwards."""
    if not openblas_pools():
        pytest.skip("no OpenBLAS built on pthreads in this process")
    monkeypatch.setattr(_blas, "_native_thread_running", lambda: True)  # (as in seen_in_core)
    from amb_fast.system import _campbell

    seen: list[tuple[set[int], list[int]]] = []
    core = _campbell._core

    class Recording:
        def __getattr__(self, name: str):  # noqa: ANN204
            return getattr(core, name)

        def speed_loops(self, *args, **kwargs):  # noqa: ANN202
            seen.append((native_threads(), blas_threads()))
            return core.speed_loops(*args, **kwargs)

    monkeypatch.setattr(_campbell, "_core", Recording())
    rig, pid, speeds = af.RotorRig.example(), af.RotorRig.example_controller(), np.linspace(0.0, 3000.0, 64)
    with threadpoolctl.threadpool_limits(2, user_api="blas"):
        user = blas_threads()
        for run in (lambda: af.campbell(rig, pid, speeds),
                    lambda: af.unbalance_response(rig, pid, speeds + 1.0, [(1e-4, 0.0, 0.0)])):  # fmt: skip
            workers = user_matmul()
            run()
            inside, counts = seen[-1]
            assert inside & workers == set()  # before the fix: the workers, spinning
            assert counts == [1] * len(user)
            assert blas_threads() == user
    assert len(seen) == 2

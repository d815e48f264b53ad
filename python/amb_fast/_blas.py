"""One BLAS thread inside functions that make thousands of small matrix operations, and no idle BLAS thread
spinning on a core while a sweep's own threads run.

OpenBLAS splits even 5x5 to 30x30 solves and exponentials across its threads, whose spin-waiting makes them many
times slower once another process holds a core (2-core machine: a six-parameter ``fit_rig`` 0.24 s alone, 10-13
s beside two busy processes, 0.24-0.40 s on one BLAS thread). After a multi-threaded call its idle pthreads
workers busy-wait about 0.1 s, even when limited to one thread: :func:`blas_parked` stops them for a sweep
(OpenBLAS's own pre-``fork`` shutdown); setting the thread count back restarts them, as after a fork.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

_controller: Any = None
_lock = threading.Lock()  # guards _depth and _limiter: the guard is process-wide, as BLAS settings are
_depth = 0  # guards entered and not yet left, on any thread
_limiter: Any = None  # the outermost guard's threadpoolctl limiter (what restores the user's settings)
_stoppers: list[Any] | None = None  # blas_thread_shutdown_ of each OpenBLAS pthreads pool
_scanned_at = -1  # len(sys.modules) when the libraries were scanned


def _blas_controller() -> Any:
    """threadpoolctl's view of the loaded BLAS libraries, scanned again after imports (scipy.linalg's OpenBLAS)."""
    global _controller, _stoppers, _scanned_at
    if _controller is None or _scanned_at != len(sys.modules):
        from threadpoolctl import ThreadpoolController

        _controller, _stoppers, _scanned_at = ThreadpoolController(), None, len(sys.modules)
    return _controller


def _take_blas_control() -> None:
    """Let this thread set OpenBLAS's thread count: threadpoolctl >= 3.6 silently ignores all but the first
    thread that set it, so a guard left on another thread would limit or restore nothing."""
    import threadpoolctl

    clear = getattr(getattr(threadpoolctl, "OpenBLASController", None), "clear_controlling_thread", None)
    if clear is not None:
        clear(force=True)


@contextlib.contextmanager
def blas_on_one_thread() -> Iterator[None]:
    """A context in which the BLAS libraries of the process (OpenBLAS, MKL, ...) run on one thread.

    Process-wide, as the libraries' settings are: the first guard entered (on any thread) limits them,
    the last one left restores what they were before it, so guards overlapping on several threads (a
    sweep on an executor of threads) never leave the process on one thread. Inside one already it does
    nothing more (a sweep's points each miss a cache that guards)."""
    global _depth, _limiter
    with _lock:
        if _depth == 0:
            controller = _blas_controller()
            _take_blas_control()
            _limiter = controller.limit(limits=1, user_api="blas")
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                limiter, _limiter = _limiter, None
                _take_blas_control()
                limiter.restore_original_limits()
                _take_blas_control()  # and leave nobody in control, as threadpoolctl's own contexts do


def blas_threads_limited() -> bool:
    """Whether some thread of the process is inside :func:`blas_on_one_thread` now."""
    return _depth > 0


def _pool_stoppers() -> list[Any]:
    """The pool shutdown of each loaded OpenBLAS on pthreads (whose idle workers spin); none for MKL, BLIS, OpenMP."""
    global _stoppers
    controller = _blas_controller()
    if _stoppers is None:
        stoppers = []
        for library in controller.info():
            if library.get("internal_api") != "openblas" or library.get("threading_layer") != "pthreads":
                continue
            with contextlib.suppress(OSError, AttributeError):
                function = ctypes.CDLL(library["filepath"]).blas_thread_shutdown_
                function.restype, function.argtypes = ctypes.c_int, []
                stoppers.append(function)
        _stoppers = stoppers
    return _stoppers


def _alone_with_blas() -> bool:
    """No other non-daemon Python thread could be in a BLAS call (stopping a pool under one could hang it)."""
    me = threading.current_thread()
    return all(t is me or t.daemon for t in threading.enumerate())


def _native_thread_running() -> bool:
    """A thread Python did not start is in state R in /proc (OpenBLAS's spinning workers); assumed without /proc."""
    try:
        tids = os.listdir("/proc/self/task")
    except OSError:
        return True
    python = {t.native_id for t in threading.enumerate()}
    for tid in tids:
        if int(tid) in python:
            continue
        try:
            with open(f"/proc/self/task/{tid}/stat") as stat:
                state = stat.read().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if state == "R":
            return True
    return False


def park_idle_blas_threads() -> bool:
    """Stop the idle (spinning) worker threads of OpenBLAS's pools, inside :func:`blas_on_one_thread` only
    (no BLAS call can start on them there), when some native thread is running. Returns whether they were
    stopped: not where another Python thread may be using BLAS, nor for libraries without such a pool."""
    if not blas_threads_limited() or not _alone_with_blas() or not _native_thread_running():
        return False  # (asleep: left alone, so nothing restarts them on leaving, and the next call is as fast)
    stoppers = _pool_stoppers()
    for stop in stoppers:
        stop()
    return bool(stoppers)


@contextlib.contextmanager
def blas_parked() -> Iterator[None]:
    """BLAS on one thread (:func:`blas_on_one_thread`) and OpenBLAS's idle workers stopped, for code whose
    own threads need every core (a sweep's core call): the user's numpy work just before leaves them
    busy-waiting for about 0.1 s. On leaving, the user's thread counts come back; pools stopped here are
    left stopped, and start again on the next multi-threaded call."""
    with blas_on_one_thread():
        parked = park_idle_blas_threads()
        yield
    if parked and not blas_threads_limited() and _alone_with_blas():
        # Restoring the thread counts started the pools again, and new workers spin for ~0.1 s: stop them,
        # so nothing spins after the sweep; the user's next multi-threaded call starts them (as after a fork).
        for stop in _pool_stoppers():
            stop()


def _guarded(context: Callable[[], contextlib.AbstractContextManager[None]]) -> Callable[[F], F]:
    """A decorator that runs a function inside ``context()``, marked ``one_blas_thread`` (tests read it)."""

    def decorate(function: F) -> F:
        @functools.wraps(function)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            with context():
                return function(*args, **kwargs)

        wrapper.one_blas_thread = True  # type: ignore[attr-defined]
        return wrapper  # type: ignore[return-value]

    return decorate


one_blas_thread = _guarded(blas_on_one_thread)
one_blas_thread.__doc__ = "Run ``function`` with the BLAS libraries of the process on one thread."
parked_blas = _guarded(blas_parked)
parked_blas.__doc__ = "Run ``function`` (a sweep on the core's threads) inside :func:`blas_parked`."

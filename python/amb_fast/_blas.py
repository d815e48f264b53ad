"""One BLAS thread inside the functions that make thousands of small matrix operations.

Calibration, design and sweeps make thousands of matrix exponentials and solves of 5x5 to 30x30
matrices. OpenBLAS splits even those across its threads, and their spin-waiting makes them many
times slower as soon as another process holds a core. Measured on the 2-core machine: a six-parameter
``fit_rig`` takes 0.24 s alone and 10-13 s beside two busy processes (0.24-0.40 s on one BLAS thread);
a 200-point sweep over ``amp_bandwidth`` on 2 threads takes 0.44 s alone and 1.2-1.4 s beside one busy
process (0.27 s and 0.37-0.40 s). Inside the decorated functions BLAS runs on the calling thread; the
process's own setting is restored on return.
"""

from __future__ import annotations

import contextlib
import functools
import threading
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

_controller: Any = None
_inside = threading.local()  # .guard: this thread is inside blas_on_one_thread


@contextlib.contextmanager
def blas_on_one_thread() -> Iterator[None]:
    """A context in which the BLAS libraries of the process (OpenBLAS, MKL, ...) run on one thread; inside
    one already (nested, on this thread) it does nothing (a sweep's points each miss a cache that guards)."""
    global _controller
    if getattr(_inside, "guard", False):
        yield
        return
    if _controller is None:  # scanning the loaded libraries costs a few ms: once per process
        from threadpoolctl import ThreadpoolController

        _controller = ThreadpoolController()
    _inside.guard = True
    try:
        with _controller.limit(limits=1, user_api="blas"):
            yield
    finally:
        _inside.guard = False


def one_blas_thread(function: F) -> F:
    """Run ``function`` with the BLAS libraries of the process on one thread."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with blas_on_one_thread():
            return function(*args, **kwargs)

    wrapper.one_blas_thread = True  # type: ignore[attr-defined]
    return wrapper  # type: ignore[return-value]

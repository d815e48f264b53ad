"""The controller matrix of N axes: ``u_i = sum_j G_ij e_j`` with each entry any SISO digital controller."""

from __future__ import annotations

import functools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Union, cast

import numpy as np

from .._linear import AnyController, controller_matrices, is_controller
from .._validate import require

#: One controller for every axis, one per axis ``(c1, ..., cN)``, or an N x N matrix ``[[c11, c12, ...],
#: ...]`` of SISO controllers (``None`` or 0 for an absent entry): ``u_i = sum_j G_ij e_j``.
ControllerSpec = Union[AnyController, "ControllerMatrix", Sequence[Any]]


@dataclass(frozen=True)
class ControllerMatrix:
    """An N x N matrix of SISO digital controllers (``None`` where there is none), at one ``fs``."""

    entries: tuple[tuple[Any, ...], ...]
    fs: float

    @property
    def size(self) -> int:
        """N."""
        return len(self.entries)

    def __iter__(self) -> Iterator[tuple[int, int, Any]]:
        for i, row in enumerate(self.entries):
            for j, c in enumerate(row):
                if c is not None:
                    yield i, j, c


def _absent(c: Any) -> bool:
    return c is None or (isinstance(c, (int, float)) and c == 0)


def controller_matrix(controller: ControllerSpec, n: int) -> ControllerMatrix:
    """Reads a controller spec (see :data:`ControllerSpec`) for ``n`` axes into a :class:`ControllerMatrix`."""
    if isinstance(controller, ControllerMatrix):
        require(controller.size == n, "controller", f"{controller.size}x{controller.size} matrix",
                f"{n}x{n} (one row and column per axis)")  # fmt: skip
        return controller
    if is_controller(controller):
        entries: list[list[Any]] = [[controller if i == j else None for j in range(n)] for i in range(n)]
    else:
        expected = f"a controller, {n} of them (one per axis), or an {n}x{n} matrix of them"
        ok = isinstance(controller, Sequence) and not isinstance(controller, str) and len(controller) == n
        require(ok, "controller", controller, expected)
        items = list(cast(Sequence[Any], controller))
        if all(_absent(c) or is_controller(c) for c in items):
            entries = [[items[i] if i == j else None for j in range(n)] for i in range(n)]
        else:
            rows = [list(row) if isinstance(row, Sequence) else [] for row in items]
            require(all(len(row) == n for row in rows), "controller", controller, expected)
            entries = rows
    entries = [[None if _absent(c) else c for c in row] for row in entries]
    present = [c for row in entries for c in row if c is not None]
    for c in present:
        require(is_controller(c), "controller entry", c, "a PID or an amb_fast.Controller (or None)")
    require(bool(present), "controller", controller, "at least one controller")
    fs = float(present[0].fs)
    require(all(float(c.fs) == fs for c in present), "controller fs", [c.fs for c in present], "equal for all entries")
    return ControllerMatrix(tuple(tuple(row) for row in entries), fs)


def block_diag(*blocks: np.ndarray) -> np.ndarray:
    """scipy.linalg.block_diag of square matrices, without its array-API overhead (~50 us a call): a
    sweep builds one loop per point."""
    sizes = [b.shape[0] for b in blocks]
    out = np.zeros((sum(sizes), sum(sizes)))
    at = 0
    for b, size in zip(blocks, sizes):
        out[at : at + size, at : at + size] = b
        at += size
    return out


@functools.lru_cache(maxsize=64)
def controller_state_space(controller: ControllerMatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The controller matrix as one discrete state space from the N probes' e[k] (m) to the N current
    commands (A), each entry's own states and delay line stacked block-diagonally; read-only, made once
    per distinct controller (a sweep of the rig keeps it)."""
    n = controller.size
    blocks = [(i, j, controller_matrices(c)) for i, j, c in controller]
    A = block_diag(*[b[2][0] for b in blocks])
    size = A.shape[0]
    B, C, D = np.zeros((size, n)), np.zeros((n, size)), np.zeros((n, n))
    at = 0
    for i, j, (_, Bc, Cc, Dc) in blocks:
        m = Bc.shape[0]
        B[at : at + m, j] = Bc[:, 0]
        C[i, at : at + m] = Cc[0]
        D[i, j] += Dc[0, 0]
        at += m
    for matrix in (A, B, C, D):
        matrix.flags.writeable = False
    return A, B, C, D

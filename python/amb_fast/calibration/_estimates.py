"""Estimate files as ``amb-fast fit`` reads them (the command itself lives in :mod:`amb_fast.cli`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._experiment import Estimate, UnexcitedLines, actual_coefficients
from ..io import load_estimate
from ._problem import FITTABLE, same_controller

__all__ = ["FITTABLE", "PLAIN_PERIODS", "read_estimate", "records", "same_controller"]  # for `amb-fast fit`

PLAIN_PERIODS = 10  # periods of a plain CSV table (which does not record them): `run`'s default

_COLUMNS = ("freq_Hz", "H_real_N_per_m", "H_imag_N_per_m", "k_std_N_per_m", "c_std_Ns_per_m")


def read_estimate(path: str | Path, *, blocks: int | None, mass: float) -> Estimate:
    """An estimate from a file that ``amb-fast run --save`` (or ``identify``) writes.

    A file written by :meth:`Estimate.save` (``.nc``, or ``.csv`` with its checksum line) is read whole
    by :func:`amb_fast.load_estimate`: it records its periods (and its controller), and ``blocks``, when
    given, must agree (``--periods``). A plain CSV table with the columns of that file holds neither the
    periods nor the known mass: ``blocks`` (the periods averaged, up to 63; default 10 as ``run``) and
    ``mass`` (kg) are given, and force and displacement amplitudes are NaN.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"estimate file {str(path)!r} does not exist")
    if records(path):
        estimate = load_estimate(path)
        if not isinstance(estimate, Estimate):  # an EstimateN's file: fitting takes one axis
            raise ValueError(
                f"{str(path)!r} holds an estimate of {len(estimate.axes)} axes; the fit takes a one-axis estimate"
            )
        if blocks is not None and blocks != estimate.blocks:
            raise ValueError(f"--periods {blocks} contradicts {str(path)!r}, which records {estimate.blocks} periods "
                             "averaged; leave --periods out for a file that records them")  # fmt: skip
        return estimate
    blocks = PLAIN_PERIODS if blocks is None else blocks
    try:
        table = np.genfromtxt(path, delimiter=",", names=True)
    except ValueError as error:
        raise ValueError(f"{path}: not a CSV estimate ({error})") from None
    names = table.dtype.names or ()
    missing = [c for c in _COLUMNS if c not in names]
    if missing:
        raise ValueError(f"{path}: columns {missing} missing; expected the CSV of `amb-fast run --save`")
    table = np.atleast_1d(table)
    freq = np.asarray(table["freq_Hz"], dtype=float)
    H = table["H_real_N_per_m"] + 1j * table["H_imag_N_per_m"]
    k, c = actual_coefficients(H, freq, mass)
    nan = np.full(freq.shape, np.nan + 0j)
    return Estimate(
        freq=freq, H=H, receptance=1.0 / H, k=k, c=c, k_smooth=k, c_smooth=c,
        k_std=np.asarray(table["k_std_N_per_m"], dtype=float), c_std=np.asarray(table["c_std_Ns_per_m"], dtype=float),
        force=nan, displacement=nan, unexcited=UnexcitedLines(np.empty(0), np.empty(0), np.empty(0)),
        periods=blocks, blocks=blocks,
    )  # fmt: skip


def records(path: Path) -> bool:
    """Whether an estimate file is one :meth:`Estimate.save` wrote (it records its periods and controller)."""
    with path.open("rb") as head:
        return path.suffix.lower() == ".nc" or head.read(10) == b"# sha256: "

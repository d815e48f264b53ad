"""Pieces that several parts of the package share instead of repeating: paper eq. 9 (``actual_coefficients``), the
run options' check (``run_options``)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import amb_fast as af
from amb_fast._experiment import actual_coefficients
from amb_fast.calibration import read_estimate


def test_eq9_is_the_estimators_and_the_plain_table_readers(tmp_path) -> None:
    rig = af.Rig.paper()
    estimate = af.run_experiment(rig, af.PID.paper(), af.schroeder_multisine(f_max=50.0), periods=3, seed=1)
    k, c = actual_coefficients(estimate.H, estimate.freq, rig.mass)
    # The core computes eq. 9 itself: the same numbers to rounding.
    np.testing.assert_allclose(k, estimate.k, rtol=1e-14)
    np.testing.assert_allclose(c, estimate.c, rtol=1e-14)
    # A plain CSV table (no checksum line) has no k, c: read_estimate makes them with eq. 9, bit for bit.
    plain = tmp_path / "plain.csv"
    columns = np.c_[estimate.freq, estimate.H.real, estimate.H.imag, estimate.k_std, estimate.c_std]
    np.savetxt(plain, columns, delimiter=",", comments="", fmt="%.17g",
               header="freq_Hz,H_real_N_per_m,H_imag_N_per_m,k_std_N_per_m,c_std_Ns_per_m")  # fmt: skip
    back = read_estimate(plain, blocks=3, mass=rig.mass)
    np.testing.assert_array_equal(back.H, estimate.H)
    np.testing.assert_array_equal(back.k, k)
    np.testing.assert_array_equal(back.c, c)
    np.testing.assert_array_equal(back.k_smooth, k)


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ({"periods": 1}, "periods must be a whole number >= 2, got 1"),
        ({"settle_periods": -1}, "settle_periods must be a whole number >= 0, got -1"),
        ({"median_window": 4}, "median_window must be odd, got 4"),
        ({"start": "settled"}, "start must be 'steady' or 'rest', got 'settled'"),
    ],
)
def test_one_check_of_the_run_options_for_experiments_and_sweeps(option, message) -> None:
    ms = af.schroeder_multisine(f_max=20.0)
    one, two, pid = af.Rig.paper(), af.TwoAxisRig.paper(), af.PID.paper()
    calls = {
        "run_experiment": lambda: af.run_experiment(one, pid, ms, **option),
        "run_experiment of N axes": lambda: af.run_experiment(two, pid, ms, **option),
        "sweep": lambda: af.sweep(one, pid, ms, kd=[3.0], progress=False, **option),
        "sweep of N axes": lambda: af.two_axis.sweep(two, pid, ms, kxy=[0.0], **option),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match=re.escape(message)):
            call()
            pytest.fail(name)

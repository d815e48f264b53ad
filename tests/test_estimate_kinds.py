"""Both estimate kinds go through one reader (io.load_estimate picks the kind from the file) and share one
base class; a loaded estimate's complex parts are the saved ones bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import amb_fast as af
from amb_fast import system


@pytest.fixture(scope="module")
def estimate() -> af.Estimate:
    return af.run_experiment(af.Rig.paper(), af.PID.paper(), af.schroeder_multisine(f0=1, f_max=20), seed=1)


@pytest.mark.parametrize("suffix", [".csv", ".nc"])
def test_negative_zero_parts_load_bit_for_bit(tmp_path, estimate, suffix) -> None:
    """``real + 1j * imag`` turned an imaginary -0.0 into +0.0 on load; the readers now build the parts."""
    H = estimate.H.copy()
    H.imag[0], H.real[1] = -0.0, -0.0
    force = estimate.force.copy()
    force.imag[2] = -0.0
    changed = dataclasses.replace(estimate, H=H, receptance=1.0 / H, force=force)
    back = af.load_estimate(changed.save(tmp_path / f"e{suffix}"))
    assert back == changed
    assert np.signbit(back.H.imag[0]) and np.signbit(back.H.real[1]) and np.signbit(back.force.imag[2])


def test_a_csv_of_no_known_kind_is_refused_naming_it(tmp_path, estimate) -> None:
    path = estimate.save(tmp_path / "e.csv")
    first, _, body = path.read_bytes().partition(b"\n")
    body = body.replace(b"# amb_fast estimate, version", b"# some other table, version", 1)
    path.write_bytes(b"# sha256: " + af.io.digest([body]).encode() + b"\n" + body)
    with pytest.raises(ValueError, match=r"path must be a \.csv file written by Estimate\.save or EstimateN\.save, "
                                         r"got '.*e\.csv'"):  # fmt: skip
        af.load_estimate(path)


def test_both_kinds_share_the_line_fields(estimate) -> None:
    names = [f.name for f in dataclasses.fields(estimate)]
    shared = ["freq", "H", "receptance", "k", "c", "k_smooth", "c_smooth", "k_std", "c_std", "force", "displacement"]
    assert names[: len(shared)] == shared
    assert [f.name for f in dataclasses.fields(system.EstimateN)][: len(shared)] == shared
    base = type(estimate).__mro__[1]
    assert base is system.EstimateN.__mro__[1] and dataclasses.is_dataclass(base)  # one base holds them


def test_an_npz_without_amb_fasts_header_is_refused_not_a_key_error(tmp_path) -> None:  # noqa: ANN001
    """A plain table (``save_estimate2``, which ``run --two-axis --save x.npz`` wrote before it wrote
    ``EstimateN.save``'s file); before, reading it back as an estimate or a sweep raised a bare
    ``KeyError: 'header'``."""
    path = tmp_path / "two.npz"
    np.savez(path, freq_Hz=np.arange(3.0), kxx_N_per_m=np.ones(3))
    with pytest.raises(ValueError, match=r"path must be an \.npz file written by EstimateN\.save, got .*two\.npz"):
        af.load_estimate(path)
    with pytest.raises(ValueError, match=r"path must be a file written by SweepResult\.save or SweepResultN\.save"):
        af.load_sweep(path)

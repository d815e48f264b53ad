"""Second moments of per-period line spectra, compared between two ways of producing them (the drawn
spectra against the loop run sample by sample and transformed)."""

from __future__ import annotations

import numpy as np


def moments(Y: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Y: (runs, periods, lines, probes). Per statistic its mean over the samples and the standard errors
    of the mean's real and imaginary parts (as one complex number): each line's variance, its covariance
    with the next period (the state carried over), between the first two probes (when there are two),
    and the pseudo-covariance E[Y Y]."""
    samples = {
        "variance": np.abs(Y) ** 2,
        "next period": Y[:, 1:] * Y[:, :-1].conj(),
        "pseudo": Y * Y,
    }
    if Y.shape[-1] > 1:
        samples["x with y"] = Y[..., 0:1] * Y[..., 1:2].conj()
    out = {}
    for name, s in samples.items():
        s = s.reshape(-1, *s.shape[2:])
        se = (s.real.std(axis=0) + 1j * s.imag.std(axis=0)) / np.sqrt(s.shape[0])
        out[name] = (s.mean(axis=0), se)
    return out


def assert_same_moments(a_spectra: np.ndarray, b_spectra: np.ndarray, within: float = 4.5) -> None:
    """Every statistic of moments() agrees within `within` standard errors of the difference, real and
    imaginary parts apart; all but the pseudo-covariance must be clearly non-zero (not trivially equal)."""
    a, b = moments(a_spectra), moments(b_spectra)
    scale = np.abs(a["variance"][0]).max()
    for name in a:
        (mean_a, se_a), (mean_b, se_b) = a[name], b[name]
        assert np.max(np.abs(mean_a)) > 1e-3 * scale or name == "pseudo", name
        for part in (np.real, np.imag):
            z = np.abs(part(mean_a) - part(mean_b)) / np.sqrt(part(se_a) ** 2 + part(se_b) ** 2 + 1e-30 * scale**2)
            assert np.max(z) < within, (name, float(np.max(z)))

"""amb_fast.controllers against independent references: scipy.signal, python-control, the PID's own
closed forms in _linear, and exact properties of the prototypes."""

from __future__ import annotations

import json
import math
import pickle
from dataclasses import replace

import numpy as np
import pytest
from scipy import signal

import amb_fast as af
from amb_fast._linear import controller_matrices, controller_response
from amb_fast.controllers import (
    Controller,
    gain,
    lead_lag,
    load_controller,
    low_pass,
    notch,
    parallel,
    pid_controller,
    pure_delay,
    second_order,
    series,
)

FS = 4000.0
F = np.geomspace(0.5, 1990.0, 97)


def close(a: np.ndarray, b: np.ndarray, rtol: float) -> None:
    """Relative to each value's magnitude (with a floor at the largest, for zeros of the response)."""
    a, b = np.asarray(a), np.asarray(b)
    scale = np.maximum(np.abs(b), 1e-6 * np.max(np.abs(b)))
    assert np.max(np.abs(a - b) / scale) < rtol


def random_zpk(rng: np.random.Generator, n_poles: int, n_zeros: int, unstable: bool) -> tuple:
    """Real-coefficient zeros and poles, well separated (conjugate pairs and real roots)."""

    def roots(count: int, rmin: float, rmax: float) -> list[complex]:
        out: list[complex] = []
        while len(out) < count:
            r, phi = rng.uniform(rmin, rmax), rng.uniform(0.2, 2.9)
            if count - len(out) >= 2 and rng.random() < 0.6:
                out += [r * np.exp(1j * phi), r * np.exp(-1j * phi)]
            else:
                out.append(r * rng.choice([-1.0, 1.0]))
        return out

    p = roots(n_poles - 1, 0.2, 0.9) if unstable else roots(n_poles, 0.2, 0.9)
    if unstable:
        p.append(1.0 if rng.random() < 0.5 else 1.2)  # an integrator, or an unstable real pole
    z = roots(n_zeros, 0.1, 1.4)
    return np.array(z), np.array(p), float(rng.uniform(0.5, 3.0))


# ---------------------------------------------------------------------------------- representations
@pytest.mark.parametrize("seed", range(12))
def test_representations_match_scipy(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 9))
    z, p, k = random_zpk(rng, n, int(rng.integers(0, n + 1)), unstable=seed % 3 == 0)
    num, den = signal.zpk2tf(z, p, k)
    num = np.concatenate([np.zeros(den.size - num.size), num])  # same length: freqz reads z^-1 powers
    _, reference = signal.freqz(num, den, worN=F, fs=FS)
    delay = seed % 3
    reference = reference * np.exp(-2j * np.pi * F / FS) ** delay
    made = {
        "tf": Controller.from_tf(num, den, FS, delay),
        "zpk": Controller.from_zpk(z, p, k, FS, delay),
        # zpk2sos pads zeros at the origin (multiplies by z^r): the extra delay takes them back out
        "sos": Controller.from_sos(signal.zpk2sos(z, p, k), FS, delay + p.size - z.size),
        "ss": Controller.from_ss(*signal.tf2ss(np.trim_zeros(num, "f"), den), FS, delay),
    }
    for name, controller in made.items():
        assert controller.order in ((n, n + n % 2) if name == "sos" else (n,)), name  # zpk2sos: whole sections
        close(controller.response(F), reference, 1e-10)
    # to_tf round trips (delay folded into den), and from_tf of it is the same controller's response
    tnum, tden = made["tf"].to_tf()
    assert tden.size == den.size + delay
    np.testing.assert_allclose(tden[: den.size], den / den[0], rtol=0, atol=1e-10 * np.max(np.abs(den)))
    np.testing.assert_allclose(tnum[delay:], num / den[0], rtol=0, atol=1e-10 * np.max(np.abs(num / den[0])))
    close(Controller.from_tf(tnum, tden, FS).response(F), reference, 1e-10)


def test_strictly_proper_tf_keeps_its_lag() -> None:
    # 1/(z - 0.5) = z^-1 / (1 - 0.5 z^-1): the response has the z^-1 (tf2sos would drop it)
    c = Controller.from_tf([1.0], [1.0, -0.5], FS)
    zi = np.exp(-2j * np.pi * F / FS)
    close(c.response(F), zi / (1 - 0.5 * zi), 1e-12)
    assert c.order == 1 and c.to_ss()[3][0, 0] == 0.0
    # relative degree 2, with a one-sample delay on top
    c = Controller.from_tf([2.0, 0.6], [1.0, -0.3, 0.1, 0.05], FS, delay=1)
    _, h = signal.freqz([0.0, 0.0, 2.0, 0.6], [1.0, -0.3, 0.1, 0.05], worN=F, fs=FS)
    close(c.response(F), h * zi, 1e-12)
    num, den = c.to_tf()
    np.testing.assert_allclose(num, [0, 0, 0, 2.0, 0.6], atol=1e-14)
    np.testing.assert_allclose(den, [1.0, -0.3, 0.1, 0.05, 0.0], atol=1e-14)


def test_response_shape_and_ss_shapes() -> None:
    c = notch(700.0)
    f = np.full((3, 4), 100.0)
    assert c.response(f).shape == (3, 4)
    assert np.ndim(c.response(100.0)) == 0
    A, B, C, D = gain(3.0).to_ss()
    assert (A.shape, B.shape, C.shape, D.shape) == ((0, 0), (0, 1), (1, 0), (1, 1))
    A, B, C, D = c.to_ss()
    assert (A.shape, B.shape, C.shape, D.shape) == ((2, 2), (2, 1), (1, 2), (1, 1))
    assert all(m.dtype == np.float64 for m in (A, B, C, D))


# -------------------------------------------------------------------------------------- from_control
def test_from_control_tustin_prewarp_matches_python_control() -> None:
    control = pytest.importorskip("control")
    wz, wp = 2 * np.pi * 80.0, 2 * np.pi * 900.0
    sys = control.tf([2.0 / wz, 2.0], [1.0 / wp, 1.0])
    f0 = 300.0
    c = Controller.from_control(sys, FS, method="tustin", prewarp=f0)
    ref = control.sample_system(sys, 1 / FS, "tustin", prewarp_frequency=2 * np.pi * f0)
    close(c.response(F), ref(np.exp(2j * np.pi * F / FS)), 1e-10)
    close(c.continuous_response(F), sys(2j * np.pi * F), 1e-12)
    # the same through a StateSpace, and the block with the same prototype
    close(Controller.from_control(control.ss(sys), FS, prewarp=f0).response(F), c.response(F), 1e-10)


@pytest.mark.parametrize("method", ["zoh", "matched", "tustin"])
def test_from_control_methods_match_python_control(method: str) -> None:
    control = pytest.importorskip("control")
    w = 2 * np.pi * 150.0
    sys = control.tf([1.0, 0.4 * w, 4 * w**2], [1.0, 0.3 * w, w**2]) * control.tf([3 * w], [1.0, 3 * w])
    c = Controller.from_control(sys, FS, method=method)
    ref = control.sample_system(sys, 1 / FS, method)
    close(c.response(F), ref(np.exp(2j * np.pi * F / FS)), 1e-9)


def test_from_control_discrete() -> None:
    control = pytest.importorskip("control")
    sys = control.tf([0.5, 0.2], [1.0, -0.6, 0.1], 1 / FS)
    c = Controller.from_control(sys)
    assert c.fs == FS and c.continuous is None
    close(c.response(F), sys(np.exp(2j * np.pi * F / FS)), 1e-12)
    c2 = Controller.from_control(control.ss(sys), FS, delay=2)
    close(c2.response(F), c.response(F) * np.exp(-2j * np.pi * F / FS) ** 2, 1e-12)
    with pytest.raises(ValueError, match="dt must be"):
        Controller.from_control(sys, 8000.0)
    mimo = control.ss(np.eye(2) * 0.5, np.eye(2), np.eye(2), np.zeros((2, 2)), 1 / FS)
    with pytest.raises(ValueError, match="sys must be SISO"):
        Controller.from_control(mimo)
    with pytest.raises(ValueError, match="fs must be given"):
        Controller.from_control(control.tf([1.0], [1.0, 1.0]))
    with pytest.raises(ValueError, match="sys must be a python-control"):
        Controller.from_control(([1.0], [1.0, 1.0]), FS)


def test_matched_with_an_integrator() -> None:
    # ki/s + kp: the pole at s = 0 maps to z = 1 and is matched as s <-> (z - 1)/T
    c = Controller.from_continuous([3.0, 200.0], [1.0, 0.0], FS, method="matched")
    T = 1 / FS
    zi = np.exp(-2j * np.pi * F / FS)
    # zero at s = -200/3 -> z = exp(-200 T/3); gain k with k (1 - e^{-200T/3}) / T = 200 (the integral gain)
    zz = np.exp(-200 / 3 * T)
    k = 200 * T / (1 - zz)
    close(c.response(F), k * (1 - zz * zi) / (1 - zi), 1e-12)


# --------------------------------------------------------------------------------------------- the PID
PIDS = [
    af.PID.paper(),
    af.PID(kp=2000.0, ki=20000.0, kd=5.0, derivative_cutoff=None, delay=0),
    af.PID(kp=2000.0, ki=0.0, kd=5.0, derivative_cutoff=800.0, delay=1),
    af.PID(kp=2000.0, ki=15000.0, kd=0.0, delay=2),
    af.PID(kp=1500.0, ki=0.0, kd=0.0, fs=10_000.0),
]


@pytest.mark.parametrize("pid", PIDS, ids=range(len(PIDS)))
def test_pid_controller_is_the_pid(pid: af.PID) -> None:
    c = pid_controller(pid)
    for mine, theirs in zip(c.to_ss(), controller_matrices(replace(pid, delay=0))):
        assert mine.shape == theirs.shape
        assert np.array_equal(mine, theirs)
    assert c.delay == pid.delay and c.fs == pid.fs
    f = F[F < pid.fs / 2]
    close(c.response(f), controller_response(pid, f, discrete=True), 1e-12)
    close(c.continuous_response(f), controller_response(pid, f), 1e-12)
    cutoff = math.inf if pid.derivative_cutoff is None else pid.derivative_cutoff
    assert c.params == {"kp": pid.kp, "ki": pid.ki, "kd": pid.kd, "derivative_cutoff": cutoff}


def test_pid_with_params() -> None:
    pid = af.PID.paper()
    c = pid_controller(pid).with_params(kp=2600.0, derivative_cutoff=math.inf)
    assert c == pid_controller(replace(pid, kp=2600.0, derivative_cutoff=None))
    assert pid_controller(pid).with_params(kd=3.0) == pid_controller(pid)
    with pytest.raises(ValueError, match="kp must be a finite number"):
        pid_controller(pid).with_params(kp=math.nan)


# -------------------------------------------------------------------------------------------- blocks
def test_notch_depth_at_centre_and_unity_away() -> None:
    for freq, depth, width in [(700.0, 0.01, None), (1800.0, 0.1, 50.0), (50.0, 0.0, 20.0), (300.0, 2.0, 30.0)]:
        c = notch(freq, width=width, depth=depth)
        assert abs(abs(c.response(freq)) - depth) < 1e-9
        assert abs(abs(c.response(freq / 30)) - 1) < 2e-2 and abs(abs(c.response(FS / 2)) - 1) < 1e-9
        assert abs(c.response(0.0) - 1) < 1e-9
        assert c.params == {"notch_freq": freq, "notch_width": width or freq / 5, "notch_depth": depth}
        close(c.continuous_response(freq), np.array(depth + 0j), 1e-12) if depth else None


@pytest.mark.parametrize("order", [1, 2, 3, 4, 7])
def test_low_pass_minus_3db_at_corner(order: int) -> None:
    for freq in (100.0, 1500.0):
        c = low_pass(freq, order=order)
        assert abs(abs(c.response(freq)) ** 2 - 0.5) < 1e-9
        assert abs(c.response(0.0) - 1) < 1e-9
        assert c.order == order
    c = low_pass(500.0, order=2, damping=0.3)
    assert abs(abs(c.response(500.0)) - 1 / 0.6) < 1e-9  # 1/(2 zeta) at the corner
    assert low_pass(500.0, order=2).params == {"low_pass_freq": 500.0, "low_pass_damping": math.sqrt(0.5)}


def test_lead_lag_and_second_order_prototypes() -> None:
    c = lead_lag(2.0, zero=100.0, pole=1000.0)
    centre = math.sqrt(100.0 * 1000.0)
    close(c.response(centre), c.continuous_response(centre), 1e-12)
    assert abs(c.response(0.0) - 2.0) < 1e-9 and abs(c.response(FS / 2) - 20.0) < 1e-9
    assert set(c.params) == {"lead_lag_gain", "lead_lag_zero", "lead_lag_pole"}
    assert abs(lead_lag().response(0.0) - 1.0) < 1e-9
    s = second_order(300.0, 500.0, num_damping=0.05, den_damping=0.5, gain=3.0)
    mid = math.sqrt(300.0 * 500.0)
    close(s.response(mid), s.continuous_response(mid), 1e-12)
    assert abs(s.response(0.0) - 3.0) < 1e-9
    assert s.params["second_order_num_damping"] == 0.05 and s.order == 2
    assert abs(abs(second_order(300.0, 300.0).response(FS / 3)) - 1) < 1e-12  # equal prototypes: unity


def test_combinations_multiply_and_add() -> None:
    pid = pid_controller(replace(af.PID.paper(), delay=1))
    n, lp = notch(700.0), low_pass(1500.0, order=2)
    tf = Controller.from_tf([0.3, 0.1], [1.0, -0.4, 0.2], FS, delay=2)
    zi = np.exp(-2j * np.pi * F / FS)
    c = pid * n * lp
    close(c.response(F), pid.response(F) * n.response(F) * lp.response(F), 1e-12)
    assert c.delay == 1 and c.order == pid.order + 4
    close(
        c.continuous_response(F),
        pid.continuous_response(F) * n.continuous_response(F) * lp.continuous_response(F),
        1e-12,
    )
    assert series(pid, n, lp) == c
    p = pid + tf + n  # delays 1, 2, 0: each branch keeps its own
    close(p.response(F), pid.response(F) + tf.response(F) + n.response(F), 1e-12)
    assert p.delay == 0 and p.continuous is None
    assert parallel(pid, tf, n) == p
    g = 2.5 * c * 0.5
    close(g.response(F), 1.25 * c.response(F), 1e-12)
    close((tf * pid).response(F), tf.response(F) * pid.response(F) * np.ones_like(zi), 1e-12)
    assert (tf * pid).delay == 3
    close((n - lp).response(F), n.response(F) - lp.response(F), 1e-12)
    close((-n + 1.0).response(F), 1.0 - n.response(F), 1e-12)
    close((pid + n).continuous_response(F), pid.continuous_response(F) + n.continuous_response(F), 1e-12)
    for combo in (c, p, g, d := pure_delay(3) * n):
        num, den = combo.to_tf()  # round trip through the polynomials, delays included
        close(Controller.from_tf(num, den, FS).response(F), combo.response(F), 1e-9)
    assert sum([n, lp]) == n + lp and 0 + n == n
    close((np.float64(2.0) * n).response(F), 2.0 * n.response(F), 1e-12)
    close(d.response(F), n.response(F) * zi**3, 1e-12)
    assert d.order == 2 and d.delay == 3


def test_params_naming_and_with_params() -> None:
    c = af.PID.paper() if False else pid_controller(af.PID.paper())
    combo = c * notch(700.0) * notch(1200.0, depth=0.1) * 2.0 * Controller.from_tf([1.0], [1.0, -0.5], FS)
    params = combo.params
    assert list(params) == [
        "kp",
        "ki",
        "kd",
        "derivative_cutoff",
        "notch_freq",
        "notch_width",
        "notch_depth",
        "notch2_freq",
        "notch2_width",
        "notch2_depth",
        "gain",
        "gain2",
    ]
    changed = combo.with_params(notch2_freq=1000.0, gain=3.0, gain2=0.5)
    expected = (
        c
        * notch(700.0)
        * notch(1000.0, width=240.0, depth=0.1)
        * 3.0
        * (0.5 * Controller.from_tf([1.0], [1.0, -0.5], FS))
    )
    close(changed.response(F), expected.response(F), 1e-12)
    assert changed.params["notch2_freq"] == 1000.0 and changed.params["notch_freq"] == 700.0
    assert combo.with_params() == combo
    with pytest.raises(ValueError, match=r"unknown controller parameter\(s\) notch3_freq; known: kp, ki"):
        combo.with_params(notch3_freq=1.0)
    two = c + c
    assert "pid2_kp" in two.params
    close(two.with_params(pid2_kp=0.0).response(F), (c + c.with_params(kp=0.0)).response(F), 1e-12)
    raw = Controller.from_sos([[1.0, 0.2, 0.0, 1.0, -0.5, 0.0]], FS)
    assert raw.params == {"gain": 1.0}
    close(raw.with_params(gain=-2.0).response(F), -2.0 * raw.response(F), 1e-12)
    assert pure_delay(2).params == {}


def test_equality_hash_pickle_repr() -> None:
    a = pid_controller(af.PID.paper()) * notch(700.0)
    b = pid_controller(af.PID.paper()) * notch(700.0)
    assert a == b and hash(a) == hash(b) and len({a, b}) == 1
    assert a != pid_controller(af.PID.paper()) * notch(710.0)
    assert pickle.loads(pickle.dumps(a)) == a
    assert pickle.loads(pickle.dumps(a)).with_params(kp=1.0) == a.with_params(kp=1.0)
    text = repr(a)
    assert text.startswith("Controller(pid(kp=2400") and "notch(freq=700" in text and "fs=4000" in text
    assert "tf(order=2" in repr(Controller.from_tf([1.0], [1.0, 0.1, 0.2], FS))
    with pytest.raises(AttributeError):
        a.fs = 1.0  # type: ignore[misc]


def test_continuous_missing_names_the_controller() -> None:
    c = Controller.from_tf([1.0], [1.0, -0.5], FS)
    assert c.continuous is None
    with pytest.raises(ValueError, match=r"controller Controller\(tf\(order=1.*has no continuous design"):
        c.continuous_response(F)
    assert (c * notch(700.0)).continuous is None
    num, den = Controller.from_continuous([1.0, 2.0], [1.0, 3.0], FS).continuous  # type: ignore[misc]
    np.testing.assert_array_equal(num, [1.0, 2.0])


# ------------------------------------------------------------------------------------------ bad input
BAD = [
    (lambda: Controller.from_tf([1.0, 2.0, 3.0], [1.0, 0.5], FS), "num must be of degree <= that of den"),
    (lambda: Controller.from_tf([1.0, math.nan], [1.0, 0.5], FS), "num must be finite"),
    (lambda: Controller.from_tf([1.0], [1.0, math.inf], FS), "den must be finite"),
    (lambda: Controller.from_tf([1.0], [0.0, 0.0], FS), "den must be not all zero"),
    (lambda: Controller.from_tf([1.0], np.poly(np.full(25, 0.5)), FS), "den must be of degree <= 24"),
    (lambda: Controller.from_tf([1.0], [1.0, 0.5], 0.0), "fs must be a finite number > 0"),
    (lambda: Controller.from_tf([1.0], [1.0, 0.5], FS, delay=-1), "delay must be a whole number >= 0"),
    (lambda: Controller.from_tf([1.0], [1.0, 0.5], FS, delay=1.5), "delay must be a whole number >= 0"),
    (lambda: Controller.from_zpk([0.1, 0.2], [0.5], 1.0, FS), "z must be"),
    (lambda: Controller.from_zpk([], [0.5 + 0.1j], 1.0, FS), "p must be real or in complex-conjugate pairs"),
    (lambda: Controller.from_zpk([], [math.nan], 1.0, FS), "p must be a 1-D sequence of finite roots"),
    (lambda: Controller.from_zpk([], [0.5], math.inf, FS), "k must be a finite number"),
    (lambda: Controller.from_sos([[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]], FS), "sos must be causal in every section"),
    (lambda: Controller.from_sos([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]], FS), "sos must be causal in every section"),
    (lambda: Controller.from_sos([[1.0, 0.0, 0.0, 1.0]], FS), "sos must be of shape"),
    (lambda: Controller.from_sos([[1.0, 0.0, 0.0, 1.0, 0.1, 0.2]] * 13, FS), "sos must be of total order <= 24"),
    (lambda: Controller.from_ss(np.eye(2), np.ones((2, 2)), np.ones((1, 2)), [[0.0]], FS), "B must be of shape"),
    (lambda: Controller.from_ss(np.eye(2), np.ones((2, 1)), np.ones((2, 2)), [[0.0]], FS), "C must be of shape"),
    (lambda: Controller.from_ss(np.eye(2), np.ones(2), np.ones(2), np.zeros((2, 1)), FS), "D must be a scalar"),
    (lambda: Controller.from_ss(np.ones((2, 3)), np.ones(2), np.ones(2), 0.0, FS), "A must be square"),
    (lambda: Controller.from_ss([[math.nan]], [1.0], [1.0], 0.0, FS), "A must be finite"),
    (lambda: Controller.from_ss(np.eye(25), np.ones(25), np.ones(25), 0.0, FS), "A must be of order <= 24"),
    (lambda: Controller.from_continuous([1.0, 0.0], [1.0], FS), "num must be of degree <= that of den"),
    (lambda: Controller.from_continuous([1.0], [1.0, 1.0], FS, method="euler"), "method must be 'tustin'"),
    (lambda: Controller.from_continuous([1.0], [1.0, 1.0], FS, prewarp=2500.0), "prewarp must be below"),
    (lambda: Controller.from_continuous([1.0], [1.0, 1.0], FS, method="zoh", prewarp=10.0), "prewarp must be None"),
    (lambda: notch(700.0, fs=1000.0), "freq must be below the Nyquist"),
    (lambda: notch(-700.0), "freq must be a finite number > 0"),
    (lambda: notch(700.0, width=0.0), "width must be a finite number > 0"),
    (lambda: notch(700.0, depth=-0.1), "depth must be >= 0"),
    (lambda: low_pass(100.0, order=0), "order must be a whole number >= 1"),
    (lambda: low_pass(100.0, order=25), "order must be <= 24"),
    (lambda: low_pass(100.0, order=1, damping=0.5), "damping must be None unless order == 2"),
    (lambda: lead_lag(zero=0.0), "zero must be a finite number > 0"),
    (lambda: lead_lag(pole=3000.0), "pole must be below the Nyquist"),
    (lambda: second_order(100.0, math.nan), "den_freq must be a finite number > 0"),
    (lambda: gain(math.nan), "value must be a finite number"),
    (lambda: notch(700.0) * notch(700.0, fs=8000.0), "fs must be the same for every block of a series"),
    (lambda: notch(700.0) + notch(700.0, fs=8000.0), "fs must be the same for every block of a parallel"),
    (lambda: series(), "blocks must be at least one Controller"),
    (lambda: series(notch(700.0), 2.0), "blocks must be Controllers"),  # type: ignore[arg-type]
    (lambda: series(*[low_pass(100.0, order=8)] * 4), "order must be <= 24"),
    (lambda: notch(700.0).with_params(width=1.0), "unknown controller parameter"),
    (lambda: notch(700.0).with_params(notch_width=-1.0), "width must be a finite number > 0"),
    (lambda: notch(700.0).response([math.nan]), "freq must be finite"),
    (lambda: pure_delay(-1), "samples must be a whole number >= 0"),
]


@pytest.mark.parametrize("make, message", BAD, ids=[m for _, m in BAD])
def test_bad_input_names_the_argument(make, message: str) -> None:  # noqa: ANN001
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        make()


# ----------------------------------------------------------------------------------- controller files
TOML = """
fs = 4000.0
delay = 1

[[block]]
type = "pid"
kp = 2400.0
ki = 20000.0
kd = 3.0
derivative_cutoff = 1000.0

[[block]]
type = "notch"
freq = 700

[[block]]
type = "low_pass"
freq = 1500.0
order = 2

[[block]]
type = "tf"
num = [0.5, 0.1]
den = [1.0, -0.3]

[[block]]
type = "continuous"
num = [1.0, 200.0]
den = [1.0, 2000.0]
method = "tustin"
prewarp = 300.0

[[block]]
type = "sos"
sos = [[1.0, 0.1, 0.0, 1.0, -0.2, 0.0]]

[[block]]
type = "lead_lag"
zero = 50.0
pole = 500.0

[[block]]
type = "second_order"
num_freq = 400.0
den_freq = 450.0

[[block]]
type = "gain"
value = 0.5
"""


def _as_json(tmp_path, text: str) -> object:  # noqa: ANN001
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        tomllib = pytest.importorskip("tomli")

    path = tmp_path / "c.json"
    path.write_text(json.dumps(tomllib.loads(text)))
    return path


def test_controller_file_toml_and_json(tmp_path) -> None:  # noqa: ANN001
    toml = tmp_path / "c.toml"
    toml.write_text(TOML)
    a, b = load_controller(toml), load_controller(_as_json(tmp_path, TOML))
    assert a == b
    expected = series(
        pid_controller(af.PID.paper()),
        notch(700.0),
        low_pass(1500.0, order=2),
        Controller.from_tf([0.5, 0.1], [1.0, -0.3], FS),
        Controller.from_continuous([1.0, 200.0], [1.0, 2000.0], FS, prewarp=300.0),
        Controller.from_sos([[1.0, 0.1, 0.0, 1.0, -0.2, 0.0]], FS),
        lead_lag(zero=50.0, pole=500.0),
        second_order(400.0, 450.0),
        gain(0.5),
    )
    assert a.delay == 1 and a.order == expected.order
    close(a.response(F), expected.response(F) * np.exp(-2j * np.pi * F / FS), 1e-12)
    assert a.params == expected.params


@pytest.mark.parametrize(
    "text, message",
    [
        ('[[block]]\ntype = "notch"\nfrq = 700.0\n', r"block 1 \(type 'notch'\): unknown key\(s\) frq; known: freq"),
        ('[[block]]\ntype = "gain"\nvalue = 1.0\n[[block]]\ntype = "notch"\n', r"block 2 .*missing key\(s\) freq"),
        ('[[block]]\ntype = "notch"\nfreq = -5.0\n', r"block 1 \(type 'notch'\): key 'freq': freq must be"),
        ('[[block]]\ntype = "pid"\nkp = "a"\nki = 0.0\nkd = 0.0\n', r"block 1 \(type 'pid'\): key 'kp': kp must"),
        ('[[block]]\ntype = "tf"\nnum = [1.0, 2.0, 3.0]\nden = [1.0]\n', r"block 1 .*key 'num': num must"),
        ('[[block]]\ntype = "wavelet"\n', r"block 1: key 'type' must be one of pid, notch"),
        ('fs = -1.0\n[[block]]\ntype = "gain"\nvalue = 1.0\n', r"fs must be a finite number > 0"),
        ('delay = 0.5\n[[block]]\ntype = "gain"\nvalue = 1.0\n', r"delay must be a whole number"),
        ("fs = 4000.0\n", r"block must be a non-empty list"),
        ('tau = 1\n[[block]]\ntype = "gain"\nvalue = 1.0\n', r"unknown top-level key\(s\) tau"),
    ],
)
def test_controller_file_errors_name_block_and_key(tmp_path, text: str, message: str) -> None:  # noqa: ANN001
    toml = tmp_path / "bad.toml"
    toml.write_text(text)
    for path in (toml, _as_json(tmp_path, text)):
        with pytest.raises(ValueError, match=message) as info:
            load_controller(path)
        assert str(path) in str(info.value)


def test_controller_file_suffix(tmp_path) -> None:  # noqa: ANN001
    path = tmp_path / "c.yaml"
    path.write_text("fs: 4000")
    with pytest.raises(ValueError, match="path must end in .toml or .json"):
        load_controller(path)


def test_typical_controller_reads_as_documented() -> None:
    c = pid_controller(af.PID.paper()) * notch(700.0) * low_pass(1500.0, order=2)
    assert c.order == 6 and c.delay == 0 and c.fs == FS
    num, den = c.to_tf()
    _, h = signal.freqz(num, den, worN=F, fs=FS)
    close(c.response(F), h, 1e-9)


def test_polynomial_products_equal_numpys() -> None:
    """The continuous designs of series and parallel blocks multiply polynomials without np.polymul's
    poly1d objects: the same numbers, leading zeros and all-zero polynomials included."""
    from amb_fast.controllers._controller import _polymul

    rng = np.random.default_rng(3)
    cases = [
        (np.zeros(1), rng.random(3)),
        (np.array([0.0, 0.0, 1.0, 2.0]), rng.random(4)),
        (rng.random(5), rng.random(2)),
        (np.array([-0.0, 3.0]), np.array([1.0])),
        (np.zeros(3), np.zeros(2)),
    ]
    for a, b in cases:
        expected, ours = np.polymul(a, b), _polymul(a, b)
        assert ours.dtype == expected.dtype
        np.testing.assert_array_equal(ours, expected)

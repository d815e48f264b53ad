"""amb_fast: simulate and identify a digitally controlled active magnetic bearing.

SI units throughout; frequencies in Hz. See ``docs/model.md`` and the README.

It implements the experiment of the paper cited in :data:`CITATION` (the one-axis electromagnetic
suspension identified with Schroeder-phased harmonic sequences); ``Rig.paper()`` / ``PID.paper()`` are
that rig, while ``Rig()`` and ``PID(...)`` are the bare model (no lags, no noise; delay 1) that tests
compare against exact answers: the README's "Defaults" table lists both side by side.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING

try:
    from . import _core  # noqa: F401
except ImportError as error:  # pragma: no cover - only without a built extension
    raise ImportError(
        "amb_fast's compiled core (_core) is not built. Install the package with `pip install .` "
        "from the project root (it compiles the C++ core), not by putting python/ on the path."
    ) from error

from ._errors import (
    IdentificationWarning,
    NoExcitationError,
    NonPeriodicExcitationWarning,
    ShortPeriodWarning,
    TouchdownError,
    UnstableLoopError,
    WeakLinesWarning,
)
from ._excitation import Multisine, schroeder_multisine
from ._experiment import Estimate, UnexcitedLines, identify, run_experiment
from ._linear import (
    StabilityMargin,
    closed_loop,
    closed_loop_poles,
    effective_coefficients,
    predict,
    sensitivity,
    stability_margin,
)
from ._params import PID, Rig
from ._simulate import Trace, simulate
from ._sweep import sweep
from ._sweep_result import SweepResult, load_sweep
from ._toml import load_rig, save_rig
from .controllers import (
    Controller,
    gain,
    lead_lag,
    load_controller,
    low_pass,
    notch,
    parallel,
    pure_delay,
    save_controller,
    second_order,
    series,
)
from .io import Recording, load_estimate, load_recording, save_recording
from .system import (
    Campbell,
    EstimateN,
    FlexibleRotor,
    RigidRotor,
    RotorRig,
    SensitivityMeasurement,
    UnbalanceResponse,
    campbell,
    identify_sensitivity,
    measure_sensitivity,
    unbalance_response,
)
from .two_axis import Estimate2, TwoAxisRig, plot_coefficients2

if TYPE_CHECKING:
    from .calibration import Design, RigFit, design_controller, fit_rig

_PLOTS = (
    "plot_actual",
    "plot_coefficients",
    "plot_coefficients_n",
    "plot_effective",
    "plot_estimate",
    "plot_family",
    "plot_overlay",
)
_CALIBRATION = ("Design", "RigFit", "design_controller", "fit_rig")


def __getattr__(name: str):  # noqa: ANN202 - loaded on first use: see below
    if name in _PLOTS:  # matplotlib, the optional extra
        from . import plots

        return getattr(plots, name)
    if name in _CALIBRATION:  # scipy.optimize and scipy.stats: half a second of every import otherwise
        from . import calibration

        return getattr(calibration, name)
    raise AttributeError(f"module 'amb_fast' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The module's names with those loaded on first use (``__getattr__``), for tab completion and ``dir``."""
    return sorted({*globals(), *_PLOTS, *_CALIBRATION})


CITATION = (
    "amb_fast reproduces the paper kept beside the project as shared/paper/one-axis-em-suspension-stiffness-damping.txt"
    " (sections 2-3, Figs. 4-10): a one-axis electromagnetic suspension under digital PID control, its actual "
    "stiffness and damping estimated in the frequency domain with Schroeder phased harmonic sequences (SPHS). The "
    "extracted text carries no title page, authors or venue (its pages are numbered from 424): cite the original "
    "publication. It builds on R. D. Williams, F. J. Keith, P. E. Allaire, 'Digital control of active magnetic "
    "bearings', IEEE Transactions on Industrial Electronics 37(1), 19-27 (1990), its reference [1]."
)

try:
    __version__ = version("amb_fast")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "unknown"

__all__ = [
    "CITATION",
    "Campbell",
    "EstimateN",
    "FlexibleRotor",
    "RigidRotor",
    "RotorRig",
    "SensitivityMeasurement",
    "campbell",
    "PID",
    "Controller",
    "Design",
    "RigFit",
    "design_controller",
    "fit_rig",
    "gain",
    "lead_lag",
    "load_controller",
    "load_rig",
    "save_controller",
    "save_rig",
    "low_pass",
    "notch",
    "parallel",
    "pure_delay",
    "second_order",
    "series",
    "Estimate",
    "Estimate2",
    "Multisine",
    "IdentificationWarning",
    "NoExcitationError",
    "NonPeriodicExcitationWarning",
    "Recording",
    "Rig",
    "ShortPeriodWarning",
    "StabilityMargin",
    "SweepResult",
    "TouchdownError",
    "Trace",
    "TwoAxisRig",
    "UnbalanceResponse",
    "UnexcitedLines",
    "UnstableLoopError",
    "WeakLinesWarning",
    "__version__",
    "closed_loop",
    "closed_loop_poles",
    "effective_coefficients",
    "identify",
    "identify_sensitivity",
    "load_estimate",
    "load_recording",
    "load_sweep",
    "measure_sensitivity",
    "plot_actual",
    "plot_coefficients",
    "plot_coefficients2",
    "plot_coefficients_n",
    "plot_effective",
    "plot_estimate",
    "plot_family",
    "plot_overlay",
    "predict",
    "run_experiment",
    "save_recording",
    "schroeder_multisine",
    "sensitivity",
    "simulate",
    "stability_margin",
    "sweep",
    "unbalance_response",
]

"""amb_fast: simulate and identify a digitally controlled active magnetic bearing.

SI units throughout; frequencies in Hz. See ``docs/model.md`` and the README.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    from . import _core  # noqa: F401
except ImportError as error:  # pragma: no cover - only without a built extension
    raise ImportError(
        "amb_fast's compiled core (_core) is not built. Install the package with `pip install .` "
        "from the project root (it compiles the C++ core), not by putting python/ on the path."
    ) from error

from ._errors import TouchdownError, UnstableLoopError
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
from ._recording import Recording, load_recording, save_recording
from ._simulate import Trace, simulate
from ._sweep import SweepResult, load_sweep, sweep
from .controllers import (
    Controller,
    gain,
    lead_lag,
    load_controller,
    low_pass,
    notch,
    parallel,
    pure_delay,
    second_order,
    series,
)

_PLOTS = ("plot_actual", "plot_coefficients", "plot_effective", "plot_estimate", "plot_family")


def __getattr__(name: str):  # noqa: ANN202 - figures load matplotlib (the optional extra) on first use
    if name in _PLOTS:
        from . import plots

        return getattr(plots, name)
    raise AttributeError(f"module 'amb_fast' has no attribute {name!r}")


try:
    __version__ = version("amb_fast")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "unknown"

__all__ = [
    "PID",
    "Controller",
    "gain",
    "lead_lag",
    "load_controller",
    "low_pass",
    "notch",
    "parallel",
    "pure_delay",
    "second_order",
    "series",
    "Estimate",
    "Multisine",
    "Recording",
    "Rig",
    "StabilityMargin",
    "SweepResult",
    "TouchdownError",
    "Trace",
    "UnexcitedLines",
    "UnstableLoopError",
    "__version__",
    "closed_loop",
    "closed_loop_poles",
    "effective_coefficients",
    "identify",
    "load_recording",
    "load_sweep",
    "plot_actual",
    "plot_coefficients",
    "plot_effective",
    "plot_estimate",
    "plot_family",
    "predict",
    "run_experiment",
    "save_recording",
    "schroeder_multisine",
    "sensitivity",
    "simulate",
    "stability_margin",
    "sweep",
]

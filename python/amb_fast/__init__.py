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

from ._params import PID, Rig
from ._simulate import Trace, simulate

try:
    __version__ = version("amb_fast")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "unknown"

__all__ = ["PID", "Rig", "Trace", "simulate", "__version__"]

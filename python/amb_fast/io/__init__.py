"""Files in and out: recordings (``_recording``, one reader per format in ``_text``, ``_mat``, ``_tdms``,
what they share in ``_channels``), estimates and sweeps as CSV/NPZ (``_results``) and NetCDF (``_netcdf``)
with SHA-256 checksums, all written atomically (``_atomic``)."""

from __future__ import annotations

from ._atomic import atomic_path, atomic_text, atomic_write
from ._channels import UNITS as CHANNEL_UNITS
from ._channels import split_unit
from ._netcdf import read_netcdf, write_dataset_netcdf, write_netcdf
from ._recording import Recording, load_recording, save_recording
from ._results import UNITS as RESULT_UNITS
from ._results import (
    digest,
    figure_metadata,
    load_estimate,
    pandas_module,
    read_npz,
    register_estimate_kind,
    save_estimate,
    version,
)
from ._text import sniff

__all__ = [
    "CHANNEL_UNITS",
    "RESULT_UNITS",
    "Recording",
    "digest",
    "figure_metadata",
    "pandas_module",
    "read_npz",
    "register_estimate_kind",
    "version",
    "write_dataset_netcdf",
    "atomic_path",
    "atomic_text",
    "atomic_write",
    "load_estimate",
    "load_recording",
    "read_netcdf",
    "save_estimate",
    "save_recording",
    "sniff",
    "split_unit",
    "write_netcdf",
]

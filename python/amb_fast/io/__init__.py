"""Files in and out: recordings (``_recording``, one reader per format in ``_text``, ``_mat``, ``_tdms``,
what they share in ``_channels``), estimates and sweeps as CSV/NPZ (``_results``) and NetCDF (``_netcdf``)
with SHA-256 checksums, all written atomically (``_atomic``)."""

from __future__ import annotations

from ._atomic import atomic_path, atomic_text, atomic_write
from ._channels import UNITS as CHANNEL_UNITS
from ._channels import split_unit
from ._netcdf import read_netcdf, split_complex, write_dataset_netcdf, write_netcdf
from ._recording import Recording, load_recording, save_recording
from ._results import (
    ONE_AXIS,
    column,
    complex_array,
    complex_variable,
    digest,
    estimate_fields_from_csv,
    estimate_fields_from_dataset,
    figure_metadata,
    load_estimate,
    pandas_module,
    read_csv,
    read_npz,
    register_estimate_kind,
    save_estimate,
    version,
    write_csv,
    write_npz,
    xarray_module,
)
from ._results import UNITS as RESULT_UNITS
from ._text import sniff

__all__ = [
    "CHANNEL_UNITS",
    "ONE_AXIS",
    "RESULT_UNITS",
    "Recording",
    "column",
    "complex_array",
    "complex_variable",
    "digest",
    "estimate_fields_from_csv",
    "estimate_fields_from_dataset",
    "figure_metadata",
    "pandas_module",
    "read_csv",
    "read_npz",
    "register_estimate_kind",
    "write_csv",
    "write_npz",
    "xarray_module",
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
    "split_complex",
    "split_unit",
    "write_netcdf",
]

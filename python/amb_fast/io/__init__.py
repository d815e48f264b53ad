"""Files in and out.

- Readers for what rigs write: the :class:`Recording` and its entry points ``load_recording`` and
  ``save_recording`` (``_recording``); one reader per format: CSV/TSV/``;`` dialects with quoted headers,
  a units row and decimal commas, read in chunks keeping only the chosen columns (``_text``); MATLAB
  v4-v7 (scipy) and v7.3 (HDF5, h5py), dSPACE ControlDesk/TRACE exports with several recordings
  (``_mat``); NI TDMS (npTDMS, ``_tdms``). What they share (``_channels``): channels by name or index,
  units scaled to SI or refused, fs from a time column, the choice among a file's recordings.
- Writers (``_results``): estimates as CSV with a metadata header, the estimate's dataset described once,
  xarray and pandas views, SHA-256 checksums checked on load.
- NetCDF (``_netcdf``): estimates and sweeps written with h5netcdf alone (the file xarray writes from their
  ``to_xarray`` Dataset, without importing xarray), xarray's writer kept as the reference; the reader, which
  checks the file's SHA-256, the dataset's and HDF5's fletcher32.
- The atomic-write helper (``_atomic``): a temporary file in the same directory, fsync, ``os.replace``.
"""

from __future__ import annotations

from ._atomic import atomic_path, atomic_text, atomic_write
from ._channels import UNITS as CHANNEL_UNITS
from ._channels import split_unit
from ._netcdf import read_netcdf, write_dataset_netcdf, write_netcdf
from ._recording import Recording, load_recording, save_recording
from ._results import (
    ONE_AXIS,
    complex_array,
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
    "complex_array",
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
    "split_unit",
    "write_netcdf",
]

"""The :class:`Recording`, :func:`load_recording` (the suffix chooses the reader: ``_text``, ``_mat``, ``_tdms``;
the MATLAB and TDMS readers return recordings, a name, ``""`` for the top level, mapped to channels) and
:func:`save_recording`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._equality import ArrayRecord
from .._validate import real, require, series
from ._atomic import atomic_write
from ._channels import _agree, _channel, _choose_recording, _file_fs, _scale, split_unit
from ._mat import _read_mat
from ._tdms import _read_tdms
from ._text import _load_text

SUFFIXES = (".csv", ".tsv", ".txt", ".mat", ".tdms", ".lvm", ".dat")  # .lvm: LabVIEW, .dat: DAQs' text exports
CHUNK_LINES = 1 << 16  # rows per chunk when writing


@dataclass(frozen=True, eq=False)
class Recording(ArrayRecord):
    """Force (N) and displacement (m) sampled at ``fs`` (Hz).

    Checked when built, by hand or by :func:`load_recording`: 1-D channels of one length (at least 2
    samples), finite samples, ``fs`` a finite rate > 0; a ``ValueError`` names the field and the value.
    The channels are stored as float64 arrays and ``fs`` as a float.

    Attributes
    ----------
    force, displacement : ndarray
        The two channels in SI units.
    fs : float
        Sampling frequency, Hz.
    source : str
        Where they came from: file, recording and channel names with the units they were scaled from
        (``'Displacement [um]' (um -> m)``) and where fs came from.
    fs_from : str
        Where ``fs`` came from, for messages: ``"the time column 'Time [s]' of rig.csv"``, ``"the 'fs'
        variable of rig.mat"`` or ``"fs= (given)"``. See :meth:`fs_note`.
    """

    force: np.ndarray
    displacement: np.ndarray
    fs: float
    source: str = ""
    fs_from: str = ""

    def __post_init__(self) -> None:
        """Checked once here, for a loaded and a hand-built recording alike: 1-D float channels of one length
        (at least 2 samples), finite samples, fs a finite rate > 0 (Hz)."""
        require(isinstance(self.source, str), "source", self.source, "a str")
        require(isinstance(self.fs_from, str), "fs_from", self.fs_from, "a str")
        where = f" ({self.source})" if self.source else ""
        force, displacement = (_samples(name, getattr(self, name)) for name in ("force", "displacement"))
        require(force.size >= 2, "force samples", force.size, f"at least 2{where}")
        require(displacement.size == force.size, "displacement samples", displacement.size,
                f"as many as force's ({force.size}){where}")  # fmt: skip
        for name, values in (("force", force), ("displacement", displacement)):
            finite = np.isfinite(values)
            if not finite.all():
                bad = int(np.argmin(finite))
                raise ValueError(f"{name} must be finite, got {float(values[bad])!r} at sample {bad}{where}")
        # frozen: the checked arrays and float replace what was given
        object.__setattr__(self, "force", force)
        object.__setattr__(self, "displacement", displacement)
        object.__setattr__(self, "fs", real("fs", self.fs, "Hz", positive=True))

    def fs_note(self) -> str:
        """``"fs 4000.1 Hz (from the time column 'Time [s]' of rig.csv)"``: to add to an error about fs or f0."""
        return f"fs {self.fs:.10g} Hz" + (f" (from {self.fs_from})" if self.fs_from else "")


def _samples(name: str, values: object) -> np.ndarray:
    """``series`` with a value that is not numbers (text, None, objects) named too."""
    try:
        return series(name, values)
    except (TypeError, ValueError) as error:
        if "shape" in str(error):
            raise
        raise ValueError(f"{name} must be samples (a 1-D array of numbers), got {type(values).__name__}") from None


def save_recording(
    path: str | Path, *, force: ArrayLike, displacement: ArrayLike, fs: float, meta: dict | None = None
) -> None:
    """Write a recording atomically: ``.csv`` (columns time, force, displacement; full precision) or ``.mat``.

    The old file, if any, is replaced only once the new one is complete. The amb_fast version and ``meta``
    (the rig, controller and seed of a simulation) go in trailing ``#`` lines of a CSV, or a text variable
    ``amb_fast`` of a ``.mat``; :func:`load_recording` skips both.
    """
    from ._results import _jsonable, trailer, version

    path = Path(path)
    suffix = path.suffix.lower()
    require(suffix in (".csv", ".mat"), "path", str(path), "a file name ending in .csv or .mat")
    # A Recording's own checks: nothing is written that load_recording would refuse (NaN, one sample).
    fs = real("fs", fs, "Hz", positive=True)
    checked = Recording(series("force", force), series("displacement", displacement), fs)
    force, displacement, fs = checked.force, checked.displacement, checked.fs
    if suffix == ".csv":

        def write(target: Path) -> None:
            with open(target, "w") as handle:
                handle.write("time,force,displacement\n")
                for start in range(0, force.size, CHUNK_LINES):
                    stop = min(start + CHUNK_LINES, force.size)
                    table = np.column_stack([np.arange(start, stop) / fs, force[start:stop], displacement[start:stop]])
                    np.savetxt(handle, table, delimiter=",", fmt="%.17g")
                handle.write(trailer(meta or {}))

        atomic_write(path, write)
    else:
        import json

        from scipy.io import savemat

        stamp = json.dumps({"amb_fast_version": version(), **_jsonable(meta or {})})
        variables = {"force": force, "displacement": displacement, "fs": fs, "amb_fast": stamp}
        atomic_write(path, lambda target: savemat(target, variables))


def load_recording(
    path: str | Path,
    *,
    force: str | int = "force",
    displacement: str | int = "displacement",
    fs: float | None = None,
    recording: str | None = None,
    time: str | int | None = "time",
    scale: Mapping[str, float] | None = None,
) -> Recording:
    """Read force and displacement channels from a rig's file.

    Formats: CSV/TSV/``.txt``/``.dat`` and LabVIEW's ``.lvm`` (``,``, ``;``, tab or blank separated;
    quoted headers and numbers; an optional units row; decimal commas; UTF-8, UTF-16 or Windows-1252;
    ``#`` comment lines; metadata lines before the header, such as LabVIEW's ``***End_of_Header***``
    blocks (its ``Y_Unit_Label`` and a ``Units`` line give units), skipped; a LabVIEW header per segment;
    no header: columns by index), MATLAB ``.mat`` v4-v7 (scipy) and v7.3 (HDF5, needs h5py)
    with top-level variables (a matrix's columns as ``name column 1``, ...), structs of numeric fields,
    dSPACE ControlDesk/TRACE exports (a struct with ``X.Data`` for time and ``Y(k).Name`` / ``Y(k).Data``
    per channel) or Simulink "Structure with time" (``time``, ``signals(k).values`` / ``.label``), and NI
    ``.tdms`` (needs ``amb_fast[tdms]``; each group is a recording). Text files are read in chunks,
    keeping only the chosen columns.

    Parameters
    ----------
    force, displacement : str or int
        Channel name (a unit in brackets or a ``_mm``-style suffix may be left out) or 0-based column
        index. Units are scaled to N and m (``kN``, ``mN``, ``mm``, ``um``, ``nm``); other units are refused.
    fs : float, optional
        Sampling frequency, Hz. If the file has a time column (or ``fs``), the two must agree within 0.1 %.
    recording : str, optional
        Which recording of a file that holds several (dSPACE exports, TDMS groups). Required then:
        channels of different recordings are never mixed.
    time : str or int or None
        The time column, by name or 0-based index. The default ``"time"`` also finds the usual names of a
        time column (``Time [s]``, ``TIME``, ``t [ms]``, ``Zeit``, ``timestamp``, LabVIEW's ``X_Value``);
        two such columns are an error naming both. Its unit (s, ms, us) scales it. fs is the clock fitted
        by least squares over the whole column: a clock rounded to its printed digits is uniform (``%.4f``
        at 4 kHz gives 4000 Hz), a gap, repeat or restart is refused naming the row. ``None`` ignores any
        time column (then ``fs`` is needed). On the command line: ``--time``.
    scale : dict, optional
        What one unit of a channel, as the file holds it, is in SI, per channel: ``{"force": 222.4,
        "displacement": 1.25e-4}`` for a DAQ that recorded volts (the transducers' calibration, N/V and m/V;
        negative for a reversed polarity). A scaled channel's own unit label (``V``, LabVIEW's ``Volts``, or
        any other) is not read; ``source`` names the factor. On the command line: ``--force-scale``,
        ``--displacement-scale``.

    Returns
    -------
    Recording
        The channels in N and m, fs, and where they came from (``source``, ``fs_from``).

    Raises
    ------
    ValueError
        A channel or time column not found (the message lists the file's columns with their indices),
        ambiguous, in a unit that is not a force/length/time, a non-uniform clock, ``fs`` disagreeing with
        the file's, or neither ``fs`` nor a time column; a row with a lost sample, rows of numbers above
        the header, units that cannot be matched to the columns, a non-finite sample.
    """
    path = Path(path)
    require(path.is_file(), "path", str(path), "an existing file")
    suffix = path.suffix.lower()
    require(suffix in SUFFIXES, "path", str(path), f"a recording ending in {', '.join(SUFFIXES)}")
    if fs is not None:
        fs = real("fs", fs, "Hz", positive=True)
    scales = dict(scale or {})
    require(set(scales) <= {"force", "displacement"}, "scale", sorted(scales), "keys 'force' and/or 'displacement'")
    for role, factor in scales.items():
        scales[role] = real(f"scale[{role!r}]", factor, "N or m per unit of the file")
        require(scales[role] != 0.0, f"scale[{role!r}]", factor, "a finite number != 0 (N or m per unit of the file)")
    name = ""
    if suffix in (".mat", ".tdms"):
        name, channels = _choose_recording(_read_mat(path) if suffix == ".mat" else _read_tdms(path), path, recording,
                                           (force, displacement))  # fmt: skip
        f_name, f_values = _channel(channels, force, "force", path)
        y_name, y_values = _channel(channels, displacement, "displacement", path)
        sizes = (np.size(f_values), np.size(y_values))
        if sizes[0] != sizes[1] or sizes[0] < 2:  # a scalar (such as 'fs') chosen by index, or two recordings'
            raise ValueError(f"{path.name}: the force {f_name!r} has {sizes[0]} samples and the displacement "
                             f"{y_name!r} {sizes[1]}: choose two channels of the same recording, of at least 2 "
                             "samples")  # fmt: skip
        names, (found, origin) = list(channels), _file_fs(channels, time, path, (f_name, y_name))
        f_values, y_values = np.array(f_values, dtype=float), np.array(y_values, dtype=float)  # scaled in place
    else:
        names, f_name, f_values, y_name, y_values, found, origin = _load_text(path, force, displacement, time, fs)
    described = []
    for values, channel, role, si in ((f_values, f_name, "force", "N"), (y_values, y_name, "displacement", "m")):
        given = scales.get(role)
        factor = given if given is not None else _scale(channel, role, path)
        if factor != 1.0:
            values *= factor
        if given is not None:
            described.append(f"{role} {channel!r} (x {given:g} {si} per unit of the file)")
        else:
            described.append(f"{role} {channel!r}" + (f" ({split_unit(channel)[1]} -> {si})" if factor != 1.0 else ""))
    fs = _agree(fs, found, path, origin, names)
    where = path.name + (f" recording {name!r}" if name else "")
    source = f"{where}: {', '.join(described)}; fs {fs:.10g} Hz " + ("given" if found is None else f"from its {origin}")
    fs_from = "fs= (given)" if found is None else f"the {origin} of {where}"
    return Recording(f_values, y_values, fs, source, fs_from)

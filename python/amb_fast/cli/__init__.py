"""The ``amb-fast`` command (also ``python -m amb_fast``).

SI units on every option: forces in N, displacements in m, gains in A/m (kp), A/(m s) (ki) and
A s/m (kd), bandwidths and frequencies in Hz, masses in kg, time constants in s.

Every expected error is one line on stderr, ``amb-fast: error: ...``, with exit status 2 for a
mistake in the command line or its input files (found before any work starts: options, output
paths, the recording) and 1 for a run that failed (touchdown, overflow, a failed write); a traceback
only with ``--debug``. Warnings are one line each, ``amb-fast: warning: ...``. No output file is
overwritten without ``--overwrite``, and every file is written atomically.

Modules: ``_options`` (shared options, output checks, the model), ``_commands`` (run, sweep, identify,
paper), ``_calibrate`` (fit, design), ``_rotor`` (rotor); the two-axis options live in :mod:`amb_fast.two_axis`.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
import traceback
import warnings
from collections.abc import Sequence
from pathlib import Path

from .._errors import TouchdownError
from ..io import version
from ..two_axis import add_two_axis_options
from ._calibrate import add_design_parser, add_fit_parser
from ._commands import (
    cmd_identify,
    cmd_paper,
    cmd_run,
    cmd_sweep,
)
from ._options import (
    GAINS,
    IDENTIFY_OPTION_NAMES,
    MODEL_OPTION_NAMES,
    PID_OPTIONS,
    UsageError,
    _add_model_options,
    _Parser,
    _values,
    cli_text,
)
from ._rotor import add_rotor_parser

AT_HELP = ("lines to tabulate (Hz, 'a,b,c'); default 10,40,100,200, or four lines spread over the band when it "
           "does not hold them")  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument("--overwrite", action="store_true", help="replace existing output files")
    common.add_argument("--debug", action="store_true", help="show the traceback of an error")
    parser = _Parser(
        prog="amb-fast",
        description="Simulate and identify a digitally controlled active magnetic bearing (paper rig by default). "
        "SI units: N, m, A, s, kg; frequencies in Hz; gains kp A/m, ki A/(m s), kd A s/m.",
    )
    parser.add_argument("--version", action="version", version=f"amb-fast {version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="{paper,run,sweep,identify,fit,design,rotor}",
                                parser_class=_Parser)  # fmt: skip

    paper = sub.add_parser("paper", parents=[common],
                           help="reproduce the paper: figures, curves (CSV, NetCDF) and claims report")  # fmt: skip
    paper.add_argument("--out", type=Path, default=Path("paper-output"), help="output folder (default paper-output)")
    paper.add_argument("--seed", type=int, default=2026, help="seed of the measurement noise")
    paper.add_argument("--no-progress", action="store_true", help="no progress lines")
    paper.set_defaults(func=cmd_paper, option_names={})

    run = sub.add_parser("run", parents=[common], help="one SPHS experiment; prints a summary")
    _add_model_options(run)
    run.add_argument("--at", type=_values, help=AT_HELP)
    run.add_argument("--save", type=Path, help="write the estimate (.csv or .nc; with --two-axis also .npz); "
                     "amb_fast.load_estimate reads it back")  # fmt: skip
    run.add_argument("--figure", type=Path, help="write a figure (.png, .pdf or .svg)")
    add_two_axis_options(run)
    run.set_defaults(func=cmd_run, option_names=MODEL_OPTION_NAMES)

    sw = sub.add_parser("sweep", parents=[common],
                        help="a grid of gains, rig fields or controller parameters to .nc, .npz or .csv")  # fmt: skip
    _add_model_options(sw, gains=False)
    for name in GAINS:
        unit, text = PID_OPTIONS[name]
        sw.add_argument(f"--{name}", type=_values, help=f"{text} values ({unit}): 'a,b,c' or 'start:stop:count'")
    sw.add_argument("--vary", action="append", default=[], metavar="NAME=VALUES",
                    help="sweep any rig field or controller parameter, as amb_fast.sweep does: a Rig field "
                    "(amp_bandwidth, kyy, mass_loading, ...), derivative_cutoff, or a --controller file's parameter "
                    "(notch_freq, ...), in its unit (Hz, N/m, kg, ...); VALUES 'a,b,c' or 'start:stop:count'; "
                    "repeat it for more axes")  # fmt: skip
    sw.add_argument("--grid", choices=["product", "zip"], default="product", help="cross the values or pair them")
    sw.add_argument("--workers", type=int, help="threads (default: all cores)")
    sw.add_argument("--out", help="output file: .nc (needs amb_fast[xarray]) or .npz, which amb_fast.load_sweep "
                    "reads back, or .csv, a table for other tools (default sweep.nc, or sweep.npz without the xarray "
                    "extra)")  # fmt: skip
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.set_defaults(func=cmd_sweep, option_names=MODEL_OPTION_NAMES)

    ident = sub.add_parser("identify", parents=[common], help="k and c from a recording (.csv/.tsv/.txt with named "
                           "columns, .mat incl. v7.3, .tdms)")  # fmt: skip
    ident.add_argument("file", type=Path, help="recording: .csv/.tsv/.txt (a header names the columns), .mat, .tdms")
    ident.add_argument("--force", default="force", help="force channel: name or 0-based column index (N, or a unit "
                       "in its name; default 'force')")  # fmt: skip
    ident.add_argument("--displacement", default="displacement", help="displacement channel: name or 0-based column "
                       "index (m, or a unit in its name)")  # fmt: skip
    ident.add_argument("--time", metavar="NAME|INDEX",
                       help="time column (s, or ms/us by its unit): name or 0-based index; 'none' to ignore it "
                       "(default: the reader's time column)")  # fmt: skip
    ident.add_argument("--recording", help="which recording of a file that holds several (dSPACE export, TDMS group)")
    ident.add_argument("--force-scale", type=float, metavar="N_PER_UNIT", help="the force channel's calibration: N "
                       "per unit of the file (a DAQ in volts: N/V); its own unit label is then not read")  # fmt: skip
    ident.add_argument("--displacement-scale", type=float, metavar="M_PER_UNIT", help="the displacement channel's "
                       "calibration: m per unit of the file (a probe in volts: m/V)")  # fmt: skip
    ident.add_argument("--fs", type=float, help="sampling frequency (Hz; default: from 'fs' or the time column, which "
                       "it must match)")  # fmt: skip
    ident.add_argument("--clearance", type=float, help="mechanical clearance (m): warn if the displacement exceeds it")
    ident.add_argument("--f0", type=float, default=1.0, help="fundamental (Hz; default 1)")
    ident.add_argument("--mass", type=float, help="known moving mass of paper eq. 9 (kg); needed unless the file "
                       "records it (a file amb_fast wrote)")  # fmt: skip
    ident.add_argument("--f-max", type=float, help="highest excited line (Hz; default: detected from the force)")
    ident.add_argument("--lines", type=_values, metavar="F1,F2,...", help="take exactly these lines (Hz, multiples of "
                       "--f0; 'a,b,c' or 'start:stop:count')")  # fmt: skip
    ident.add_argument("--settle-periods", type=int, default=0,
                       help="periods to skip at the start (a warning says when a transient is left in)")  # fmt: skip
    ident.add_argument("--median-window", type=int, default=5, help="median filter width (lines, odd)")
    ident.add_argument("--at", type=_values, help=AT_HELP)
    ident.add_argument("--figure", type=Path, help="write the figure here (.png, .pdf or .svg) instead of "
                       "OUT/estimate.png")  # fmt: skip
    ident.add_argument("--out", type=Path, default=Path("identify-output"), help="output folder (estimate.csv, "
                       "estimate.png)")  # fmt: skip
    ident.set_defaults(func=cmd_identify, option_names=IDENTIFY_OPTION_NAMES)

    add_fit_parser(sub, parents=[common])
    add_design_parser(sub, parents=[common])
    add_rotor_parser(sub, parents=[common])
    return parser


def _one_line(names: dict[str, str]):  # noqa: ANN202
    """``warnings.showwarning`` printing one line, with the library's parameter names as the command's options."""

    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int, file=None,
             line=None) -> None:  # noqa: ANN001  # fmt: skip
        text = " ".join(str(message).split())
        print(f"amb-fast: warning: {cli_text(text, names)}", file=sys.stderr)

    return show


EXPECTED = (UsageError, ValueError, OSError, ImportError, TouchdownError, OverflowError, MemoryError)


#: A negative number in any notation argparse would mistake for an option ("-1e4", "-.5", "-inf").
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf$", re.IGNORECASE)


def _join_negative_values(argv: Sequence[str]) -> list[str]:
    """``--kyx -1e4`` -> ``--kyx=-1e4``: argparse reads only plain negatives ("-5", "-0.5") as values."""
    out: list[str] = []
    for token in argv:
        if _NEGATIVE_NUMBER.match(token) and out and out[-1].startswith("--") and "=" not in out[-1]:
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(_join_negative_values(sys.argv[1:] if argv is None else argv))
    args.phase = "check"
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():  # a warning is one line on stderr, whatever the interpreter's filters
            warnings.simplefilter("default", UserWarning)
            warnings.showwarning = _one_line(getattr(args, "option_names", {}))
            args.func(args)
    except KeyboardInterrupt:
        print("amb-fast: interrupted", file=sys.stderr)
        return 130
    except Exception as error:
        if args.debug:
            traceback.print_exc()
        status = 2 if args.phase == "check" else 1
        if isinstance(error, EXPECTED):
            text = " ".join(str(error).split()) or type(error).__name__
            if not isinstance(error, UsageError):  # the library's words: its parameter names become options
                text = cli_text(text, getattr(args, "option_names", {}))
            print(f"amb-fast: error: {text}", file=sys.stderr)
        else:
            print(f"amb-fast: error: internal error {type(error).__name__}: {error} (please report it; --debug shows "
                  "the traceback)", file=sys.stderr)  # fmt: skip
            status = 1
        return status
    print(f"done in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""What every benchmark script shares: median timing, the command line, the printed table and JSON."""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np


def median_seconds(
    run: Callable[[], object], repeats: int, *, warm_up: bool = True, clock: Callable[[], float] = time.perf_counter
) -> float:
    """Median time of ``repeats`` calls (after one untimed call): the machine is noisy. ``clock`` is wall
    time by default; ``time.process_time`` (CPU time of this process) leaves out the time spent waiting
    for a core on a shared machine, for single-threaded work."""
    if warm_up:
        run()
    times = []
    for _ in range(repeats):
        start = clock()
        run()
        times.append(clock() - start)
    return float(np.median(times))


def arguments(doc: str, name: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short smoke run (CI)")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / f"{name}.json")
    return parser.parse_args()


def report(out: Path, measured: dict[str, float], ratios: dict[str, float], unit: str, scale: float) -> None:
    """Print the measurements (times ``scale``, in ``unit``) and the ratios; write both as JSON."""
    for label, value in measured.items():
        print(f"{label:58s} {value * scale:12.4g} {unit}")
    for label, value in ratios.items():
        print(f"{label:58s} {value:12.4g}")
    out.parent.mkdir(parents=True, exist_ok=True)
    payload = {"machine": platform.platform(), "processor": platform.processor(), "quick": "--quick" in sys.argv[1:],
               "measured": measured, "ratios": ratios}  # fmt: skip
    out.write_text(json.dumps(payload, indent=2))
    print(f"wrote {out}")

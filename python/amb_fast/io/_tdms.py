"""NI TDMS recordings (npTDMS): each group is a recording."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._channels import _scale, split_unit, symbol


def _read_tdms(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """The groups' channels, named with their ``unit_string`` (``Gap [mm]``), and ``fs`` from their
    ``wf_increment``: one rate, or one per channel (NaN without one) when they differ."""
    try:
        from nptdms import TdmsFile
    except ImportError as error:
        raise ImportError(f"{path.name} is an NI TDMS file: reading it needs npTDMS: pip install 'amb_fast[tdms]'") \
            from error  # fmt: skip
    groups: dict[str, dict[str, np.ndarray]] = {}
    with TdmsFile.open(path) as tdms:
        for group in tdms.groups():
            channels: dict[str, np.ndarray] = {}
            rates = []
            for channel in group.channels():
                unit = symbol(str(channel.properties.get("unit_string") or ""))
                named = split_unit(channel.name)[1]
                if unit and named and _factor(unit, path) != _factor(named, path):  # never one of them guessed
                    raise ValueError(f"{path.name}: the channel {channel.name!r} of group {group.name!r} has "
                                     f"unit_string {unit!r}, not the unit of its name: which is right is not known; "
                                     "correct one of them")  # fmt: skip
                name = channel.name if not unit or named else f"{channel.name} [{unit}]"
                channels[name] = np.asarray(channel[:], dtype=float)
                increment = channel.properties.get("wf_increment")
                rates.append(1.0 / float(increment) if increment else np.nan)
            known = {rate for rate in rates if np.isfinite(rate)}
            if known and "fs" not in channels:  # after the channels: their 0-based indices stay the file's
                channels["fs"] = np.asarray(known.pop()) if len(known) == 1 else np.array(rates)
            groups[group.name] = channels
    return groups


def _factor(unit: str, path: Path) -> tuple[str, float] | str:
    """A unit's quantity and factor to SI, to compare two spellings (``m`` and ``meters``); else itself."""
    for quantity in ("force", "displacement", "time"):
        try:
            return quantity, _scale(f"x [{unit}]", quantity, path)
        except ValueError:
            continue
    return unit.casefold()

"""NI TDMS recordings (npTDMS): each group is a recording."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._channels import split_unit


def _read_tdms(path: Path) -> dict[str, dict[str, np.ndarray]]:
    try:
        from nptdms import TdmsFile
    except ImportError as error:
        raise ImportError(f"{path.name} is an NI TDMS file: reading it needs npTDMS: pip install 'amb_fast[tdms]'") \
            from error  # fmt: skip
    groups: dict[str, dict[str, np.ndarray]] = {}
    with TdmsFile.open(path) as tdms:
        for group in tdms.groups():
            channels: dict[str, np.ndarray] = {}
            fs = None
            for channel in group.channels():
                unit = channel.properties.get("unit_string")
                name = channel.name if not unit or split_unit(channel.name)[1] else f"{channel.name} [{unit}]"
                channels[name] = np.asarray(channel[:], dtype=float)
                increment = channel.properties.get("wf_increment")
                if increment and fs is None:
                    fs = np.asarray(1.0 / float(increment))
            if fs is not None and "fs" not in channels:  # after the channels: their 0-based indices stay the file's
                channels["fs"] = fs
            groups[group.name] = channels
    return groups

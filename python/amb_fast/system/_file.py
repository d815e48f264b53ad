"""Rotor files: a rotor, its axes' chain and its controller in TOML (the format of controller files).

    [rotor]                        # RigidRotor's fields, SI: kg, kg m^2, m from the centre of mass, rad/s
    mass = 10.0
    transverse_inertia = 0.2146
    polar_inertia = 0.0125
    bearings = [-0.2, 0.2]
    sensors = [-0.23, 0.23]
    process = [[0.1, 3e3, -3e3, 0.0, 0.0]]   # optional: (z, kxy, kyx, cxy, cyx)

    [axes]                         # every axis' chain: Rig.paper() with these fields changed
    amp_bandwidth = 3000.0

    [controller]                   # a PID on every axis: RotorRig.example_controller() with these changed
    kp = 3000.0

Every section is optional: an empty file is :meth:`RotorRig.example` under its example controller.
"""

from __future__ import annotations

import os
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from .._params import PID, Rig
from .._toml import read_table
from ._rotor import RigidRotor, RotorRig

_SECTIONS = {"rotor": RigidRotor, "axes": Rig, "controller": PID}


def load_rotor(path: str | os.PathLike[str]) -> tuple[RotorRig, PID]:
    """The rotor rig and its controller from a rotor file (TOML, or the same tables in JSON: see the module's
    docstring). Errors name the file and the section and key."""
    data = read_table(path, "rotor file")
    where = f"rotor file {str(Path(path))!r}"
    for section in data:
        if section not in _SECTIONS:
            raise ValueError(f"{where}: unknown section [{section}] (expected {', '.join(_SECTIONS)})")
    values: dict[str, dict[str, Any]] = {}
    for section, kind in _SECTIONS.items():
        values[section] = table = data.get(section, {})
        if not isinstance(table, dict):
            raise ValueError(f"{where}: [{section}] must be a table")
        known = {f.name for f in fields(kind)} - ({"mass"} if kind is Rig else set())
        unknown = sorted(set(table) - known)
        if unknown:
            raise ValueError(f"{where}: unknown key {unknown[0]!r} in [{section}] (known: {sorted(known)})")
    try:
        rotor = replace(RotorRig.example().rotor, **values["rotor"])  # type: ignore[type-var]  # a RigidRotor
        axis = replace(Rig.paper(), **values["axes"])
        controller = replace(RotorRig.example_controller(), **values["controller"])
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: {error}") from None
    return RotorRig(rotor, axis), controller

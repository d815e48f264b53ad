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
from ._rotor import RigidRotor, RotorRig

_SECTIONS = {"rotor": RigidRotor, "axes": Rig, "controller": PID}


def load_rotor(path: str | os.PathLike[str]) -> tuple[RotorRig, PID]:
    """The rotor rig and its controller from a rotor file (see the module's docstring). Errors name the file
    and the section and key."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"rotor file must be an existing file, got {str(path)!r}")
    if path.suffix.lower() != ".toml":
        raise ValueError(f"rotor file must end in .toml, got {str(path)!r}")
    import tomllib

    try:
        with open(path, "rb") as file:
            data = tomllib.load(file)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"rotor file {path}: not valid TOML ({error})") from None
    for section in data:
        if section not in _SECTIONS:
            raise ValueError(f"rotor file {path}: unknown section [{section}] (expected {', '.join(_SECTIONS)})")
    values: dict[str, dict[str, Any]] = {}
    for section, kind in _SECTIONS.items():
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise ValueError(f"rotor file {path}: [{section}] must be a table")
        known = {f.name for f in fields(kind)} - ({"mass"} if kind is Rig else set())
        for key in table:
            if key not in known:
                raise ValueError(f"rotor file {path}: unknown key {key!r} in [{section}] (known: {sorted(known)})")
        values[section] = table
    example = RotorRig.example()
    try:
        rotor_fields = {**{f.name: getattr(example.rotor, f.name) for f in fields(RigidRotor)}, **values["rotor"]}
        rotor_fields["process"] = tuple(tuple(p) for p in rotor_fields["process"])
        rotor = RigidRotor(**rotor_fields)
        axis = replace(Rig.paper(), **values["axes"])
        controller = replace(RotorRig.example_controller(), **values["controller"])
    except (TypeError, ValueError) as error:
        raise ValueError(f"rotor file {path}: {error}") from None
    return RotorRig(rotor, axis), controller

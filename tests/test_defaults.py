"""The README's table of defaults, `Rig()` / `PID()` beside `Rig.paper()` / `PID.paper()`, is the code's."""

from __future__ import annotations

import ast
import dataclasses
import re
from pathlib import Path

import pytest

import amb_fast as af

README = (Path(__file__).parents[1] / "README.md").read_text()


def table(header: str) -> dict[str, tuple[object, object]]:
    block = README[README.index(header) :].split("\n\n")[0]
    rows = re.findall(r"^\| (\w+) \| (.+?) \| (.+?) \|$", block, re.M)
    return {name: (ast.literal_eval(a), ast.literal_eval(b)) for name, a, b in rows if name != "field"}


@pytest.mark.parametrize(
    ("header", "plain", "paper"),
    [
        ("| field | `Rig()` | `Rig.paper()` |", af.Rig(), af.Rig.paper()),
        (
            "| field | `PID(kp=2400.0, ki=20000.0, kd=3.0)` | `PID.paper()` |",
            af.PID(2400.0, 20000.0, 3.0),
            af.PID.paper(),
        ),
    ],
)
def test_the_defaults_table_is_the_code(header, plain, paper) -> None:
    rows = table(header)
    fields = [f.name for f in dataclasses.fields(plain)]
    assert sorted(rows) == sorted(fields)
    for name, (a, b) in rows.items():
        assert getattr(plain, name) == a, name
        assert getattr(paper, name) == b, name


def test_the_paper_is_cited() -> None:
    assert "shared/paper/one-axis-em-suspension-stiffness-damping.txt" in af.CITATION
    assert "amb_fast.CITATION" in README and "CITATION" in af.__doc__

"""Every row of docs/errors.md: the call raises what the table says, with the message it quotes."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import amb_fast as af

ROWS = [
    row
    for row in re.findall(
        r"^\| `(.+?)` \| (\w+) \| (.+?) \|$", (Path(__file__).parents[1] / "docs" / "errors.md").read_text(), re.M
    )
]
CLASSES = {"ValueError": ValueError, "OverflowError": OverflowError, "UnstableLoopError": af.UnstableLoopError,
           "TouchdownError": af.TouchdownError, "NoExcitationError": af.NoExcitationError, "TypeError": TypeError,
           "OSError": OSError}  # fmt: skip


def test_the_table_is_there() -> None:
    assert len(ROWS) >= 60


@pytest.mark.parametrize(("call", "raises", "message"), ROWS, ids=[r[0][:60] for r in ROWS])
def test_documented_error(call: str, raises: str, message: str, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    namespace = {"af": af, "np": np, "ms": af.schroeder_multisine()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # a truncation warning is not what is tested here
        with pytest.raises(CLASSES[raises]) as info:
            eval(call, namespace)  # noqa: S307 - the calls are this project's own documentation
    assert message in str(info.value)

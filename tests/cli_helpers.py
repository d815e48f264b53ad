"""What the command's tests share: the command run in this process, and its one-line error."""

from __future__ import annotations

from amb_fast import cli


def run(capsys, *args: str) -> tuple[int, str, str]:  # noqa: ANN001
    """The command in this process: (exit status, stdout, stderr)."""
    try:
        status = cli.main(list(args))
    except SystemExit as done:  # argparse: --version, --help and its own errors
        status = int(done.code or 0)
    out, err = capsys.readouterr()
    return status, out, err


def one_error_line(err: str) -> str:
    """The error's one line, checked to be the only one, in the command's form and without a traceback."""
    lines = err.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("amb-fast: error: ") and "Traceback" not in err
    return lines[0]

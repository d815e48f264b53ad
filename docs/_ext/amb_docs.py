"""Content the documentation build generates, so that it stays true, and a check of the API reference.

On ``builder-inited`` (before any page is read):

- ``_generated/paper/``: the paper's study run on the virtual rig (``amb_fast.paper``): Figures 4-10,
  the curves as CSV/NetCDF, ``setup.md`` (what was run) and ``claims.md`` (the claims table).
- ``_generated/cli/*.md``: the output of the commands the guide pages show (``CLI_RUNS``), run by the
  build with this Python, so that the pages show what today's code prints.
- ``_generated/speed.md``: the benchmark tables, from the JSON files ``bench/*.py --out`` writes.
  Preferred source: ``bench/results/<name>.json`` (a full run, ``python bench/<name>.py``, saved on the
  machine that builds the docs). Without it the build runs ``bench/<name>.py --quick`` itself into
  ``_generated/bench/`` (kept between builds; delete the folder to measure again) and says so on the page.

On ``autodoc-process-docstring`` (before numpydoc): a bare ``|`` outside an inline literal, as in
``|Y/F|`` or ``|z| >= 1``, is escaped, so docutils reads it as a character and not as a substitution
reference. The docstrings mean absolute values; this keeps their plain-text form readable in ``help()``.

On ``env-check-consistency``: every name in ``amb_fast.__all__`` must have been documented (an
``auto*`` or ``py:*`` directive for ``amb_fast.<name>``), and every ``examples/plot_*.py`` must have
produced a figure; anything missing is a warning, so ``-W`` fails.
"""

from __future__ import annotations

import datetime
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parent.parent
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"

# Each benchmark: what it measures, the unit its seconds are shown in and the scale to get there.
BENCHMARKS = {
    "bench_experiment": ("The paper experiment as users run it, against a vectorised scipy script", "ms", 1e3),
    "bench_two_axis": ("Two axes: one two-axis experiment against one one-axis experiment", "ms", 1e3),
    "bench_core": ("The simulation loop, time per simulated sample", "ns/sample", 1e9),
    "bench_identify": ("One experiment and identification of a long recording", "ms", 1e3),
    "bench_sweep": ("Gain sweeps: throughput, thread scaling, vectorised predict, memory", "s", 1.0),
}

# Commands whose output a page includes (``{include} _generated/cli/<name>.md``): name -> arguments.
CLI_RUNS = {
    "run_two_axis": ["run", "--two-axis", "--kxy=1e4", "--kyx=-1e4", "--seed", "1"],
}


def _paper(out: Path) -> None:
    """Run the paper's study and write its figures, curves, setup and claims table into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    from amb_fast import claims as claim_checks
    from amb_fast import paper
    from amb_fast._study import paper_study

    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    study = paper_study(seed=2026, progress=False)
    paper.write_curves(study, out)
    paper.write_figures(study, out)
    claims = study.claims()
    table = claim_checks.markdown(claims)
    setup = paper.report(study, "").split("\n", 2)[2].strip()  # drop the report's own heading
    (out / "setup.md").write_text(setup + "\n")
    (out / "claims.md").write_text(table)
    failed = [c.id for c in claims if not c.reproduced]
    if failed:
        logger.warning(f"amb_docs: the paper's observations {failed} are not reproduced (see the paper page)")
    logger.info(f"amb_docs: paper study and figures in {time.perf_counter() - start:.1f} s")


def _bench_json(name: str) -> tuple[dict, str]:
    """The benchmark's JSON and a sentence saying where it came from."""
    saved = ROOT / "bench" / "results" / f"{name}.json"
    if saved.is_file():
        when = datetime.datetime.fromtimestamp(saved.stat().st_mtime).strftime("%Y-%m-%d %H:%M")
        return json.loads(saved.read_text()), f"read from `bench/results/{name}.json`, written {when}"
    out = GENERATED / "bench" / f"{name}.json"
    if not out.is_file():
        out.parent.mkdir(parents=True, exist_ok=True)
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, str(ROOT / "bench" / f"{name}.py"), "--quick", "--out", str(out)],
            check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
        )  # fmt: skip
        logger.info(f"amb_docs: {name} --quick in {time.perf_counter() - start:.1f} s")
    when = datetime.datetime.fromtimestamp(out.stat().st_mtime).strftime("%Y-%m-%d %H:%M")
    return json.loads(out.read_text()), f"run by the documentation build, {when}"


def _number(value: float) -> str:
    return f"{value:.4g}"


def _speed(out: Path) -> None:
    """The benchmark tables as Markdown, one section per benchmark script."""
    parts = []
    for name, (title, unit, scale) in BENCHMARKS.items():
        data, source = _bench_json(name)
        kind = {True: "a `--quick` smoke run", False: "a full run"}.get(data.get("quick"), "a run")
        rows = [f"### {title}", "", f"`python bench/{name}.py`: {kind}, {source}, on `{data['machine']}`.", ""]
        rows += ["| measured | value |", "|---|---:|"]
        rows += [f"| {label} | {_number(value * scale)} {unit} |" for label, value in data["measured"].items()]
        rows += ["", "| ratio or rate | value |", "|---|---:|"]
        rows += [f"| {label} | {_number(value)} |" for label, value in data["ratios"].items()]
        parts.append("\n".join(rows))
    out.write_text("\n\n".join(parts) + "\n")


def _cli(out: Path) -> None:
    """Run each command of ``CLI_RUNS`` and write it with its output as a Markdown code block."""
    out.mkdir(parents=True, exist_ok=True)
    for name, args in CLI_RUNS.items():
        done = subprocess.run([sys.executable, "-m", "amb_fast", *args], check=True, cwd=ROOT,
                              capture_output=True, text=True)  # fmt: skip
        shown = " ".join(["amb-fast", *args])
        (out / f"{name}.md").write_text(f"```text\n$ {shown}\n{done.stdout.rstrip()}\n```\n")


def generate(app: Sphinx) -> None:
    GENERATED.mkdir(exist_ok=True)
    if os.environ.get("AMB_DOCS_REUSE_PAPER") and (GENERATED / "paper" / "claims.md").is_file():
        logger.info("amb_docs: reusing _generated/paper (AMB_DOCS_REUSE_PAPER is set)")
    else:
        _paper(GENERATED / "paper")
    _cli(GENERATED / "cli")
    _speed(GENERATED / "speed.md")


def _escape_bars(line: str) -> str:
    """Escape ``|`` outside ``double-backtick`` literals (the only place docutils keeps backslashes)."""
    parts = re.split(r"(``.*?``)", line)
    return "".join(part if part.startswith("``") else re.sub(r"(?<!\\)\|", r"\\|", part) for part in parts)


def escape_bars(app: Sphinx, what: str, name: str, obj: object, options: dict, lines: list[str]) -> None:
    if name.startswith("amb_fast"):
        lines[:] = [_escape_bars(line) for line in lines]


def check_public_names(app: Sphinx, env) -> None:  # noqa: ANN001
    import amb_fast

    documented = set(env.get_domain("py").objects)
    missing = [name for name in amb_fast.__all__ if f"amb_fast.{name}" not in documented]
    if missing:
        logger.warning(f"amb_docs: amb_fast.__all__ names without an API reference section: {', '.join(missing)}")


def check_gallery_figures(app: Sphinx, env) -> None:  # noqa: ANN001
    """Every gallery script ran (sphinx-gallery aborts on an error) and produced at least one figure."""
    images = DOCS / "auto_examples" / "images"
    missing = [p.name for p in sorted((ROOT / "examples").glob("plot_*.py"))
               if not (images / f"sphx_glr_{p.stem}_001.png").is_file()]  # fmt: skip
    if missing:
        logger.warning(f"amb_docs: gallery examples without a figure: {', '.join(missing)}")


def setup(app: Sphinx) -> dict:
    app.connect("builder-inited", generate)
    app.connect("autodoc-process-docstring", escape_bars, priority=400)  # numpydoc runs at 500
    app.connect("env-check-consistency", check_public_names)
    app.connect("env-check-consistency", check_gallery_figures)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

"""Every example model through every analysis (issue 62): each works or refuses with a located reason.

The commands run as a user types them, at their defaults but for small budgets (in process, through
:func:`symkin.cli.main`): ``workspace``, ``gci``, ``rate``, ``simulate`` and ``view`` on the committed
``generated/<model>``, ``excite`` and ``identify`` on ``models/<model>.yaml`` (derived on the fly, as a user's
model file is).  ``identify`` reads the run ``excite`` designed, with efforts drawn at random (the estimate is
meaningless, the workflow is not).  A refusal is exit code 2 with a message that names the model and says
what to do; docs/analysis.md ("Every example model through every analysis") lists each, and the test holds the
list to what the commands do: a refusal that goes away or a new one fails until the table is brought up to date.
"""

from __future__ import annotations

import contextlib
import csv
import io
import re
from pathlib import Path

import numpy as np
import pytest

from conftest import EXAMPLE_MODELS, GENERATED_DIR, MODELS_DIR, ROOT
from symkin.cli import main

DOCUMENT = ROOT / "docs" / "analysis.md"
SECTION = "## Every example model through every analysis"
ANALYSES = ("workspace", "gci", "rate", "simulate", "view", "excite", "identify")
#: The table's rows: | model | analysis | what the refusal says (a part of its message) |
ROW = re.compile(r"^\|\s*`?(\w+)`?\s*\|\s*`?(\w+)`?\s*\|\s*(.+?)\s*\|\s*$")


def documented_refusals() -> dict[tuple[str, str], str]:
    """{(model, analysis): the quoted part of the refusal's message} from the table of :data:`SECTION`."""
    text = DOCUMENT.read_text()
    section = text[text.index(SECTION):]
    section = section[:section.find("\n## ", 1)] if "\n## " in section[1:] else section
    refusals = {}
    for line in section.splitlines():
        match = ROW.match(line)
        if match and match.group(1) in EXAMPLE_MODELS:
            refusals[match.group(1), match.group(2)] = match.group(3).strip("`")
    return refusals


def command_lines(name: str, out: Path) -> dict[str, list[str]]:
    """The command line of each analysis on the example model ``name``, writing under ``out``."""
    generated, model = str(GENERATED_DIR / name), str(MODELS_DIR / f"{name}.yaml")
    return {
        "workspace": ["workspace", generated, "-n", "2048", "--no-figure"],
        "gci": ["gci", generated, "-n", "2048", "--seed", "0"],
        "rate": ["rate", generated, "-n", "256", "--no-figure", "-o", str(out / "rate")],
        "simulate": ["simulate", generated, "--duration", "0.02", "--no-figure", "-o", str(out / "simulate")],
        "view": ["view", generated, "--workspace", "256", "-o", str(out / "view.html")],
        "excite": ["excite", model, "--max-velocity", "1", "--max-acceleration", "5", "--period", "4",
                   "--harmonics", "2", "--max-iterations", "3", "--no-figure", "-o", str(out / "excite")],
        "identify": ["identify", model, str(out / "run.csv"), "--no-figure", "-o", str(out / "identify")],
    }


def run(argv: list[str]) -> tuple[int, str]:
    """(exit code, standard error) of ``symkin ARGV`` run in this process."""
    errors = io.StringIO()
    try:
        with contextlib.redirect_stderr(errors), contextlib.redirect_stdout(io.StringIO()):
            code = main(argv)
    except SystemExit as exit_:  # argparse's exit, a refused input
        code = int(exit_.code or 0)
    return code, errors.getvalue()


def write_run(excitation: Path, run_file: Path) -> None:
    """The designed run (excitation.csv: t, q_, qd_, qdd_ of every device joint) with random efforts tau_."""
    with open(excitation) as table:
        rows = list(csv.reader(table))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    joints = [column[2:] for column in header if column.startswith("q_")]
    efforts = np.random.default_rng(0).normal(size=(len(values), len(joints)))
    with open(run_file, "w", newline="") as table:
        writer = csv.writer(table)
        writer.writerow(header + [f"tau_{joint}" for joint in joints])
        writer.writerows(np.hstack([values, efforts]).tolist())


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_every_analysis_works_or_refuses_as_documented(name, tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_QUIET", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(tmp_path)
    documented = {analysis: text for (model, analysis), text in documented_refusals().items() if model == name}
    lines, refused = command_lines(name, tmp_path), {}
    for analysis in ANALYSES:
        if analysis == "identify" and "excite" not in refused:
            write_run(tmp_path / "excite" / "excitation.csv", tmp_path / "run.csv")
        code, errors = run(lines[analysis])
        assert code in (0, 2), f"symkin {analysis} {name}: exit code {code}\n{errors[-2000:]}"
        if code == 2:
            refused[analysis] = errors
            assert name in errors, f"symkin {analysis} {name} refuses without naming the model: {errors}"
    assert sorted(refused) == sorted(documented), \
        f"{name}: refused {sorted(refused)}, docs/analysis.md lists {sorted(documented)}:\n" + \
        "\n".join(f"{analysis}: {errors.strip()}" for analysis, errors in refused.items())
    for analysis, text in documented.items():
        assert " ".join(text.split()) in " ".join(refused[analysis].split()), \
            f"{name} {analysis}: the refusal says {refused[analysis]!r}, docs/analysis.md quotes {text!r}"


def test_the_table_names_example_models_and_analyses():
    refusals = documented_refusals()
    assert refusals, "docs/analysis.md has no table of refusals"
    assert {analysis for _, analysis in refusals} <= set(ANALYSES)
    assert {model for model, _ in refusals} <= set(EXAMPLE_MODELS)

"""The stability report's files (issue 19, audit): written atomically, drawn without pyplot."""

from __future__ import annotations

import subprocess
import sys

import pytest

from symkin.stability.harness import Record, StabilityRun
from symkin.stability.report import write_csv, write_figure
from tests.conftest import ROOT


def small_run() -> StabilityRun:
    records = [Record("fk", family, "", parameter, kappa, 1e-16 * kappa)
               for family, parameter in (("random", 1.0), ("scale", 1e-3), ("scale", 1e3), ("float32", 1.0))
               for kappa in (1.0, 10.0, 1e3)]
    return StabilityRun("arm", ("fk",), {}, [], records)


class _Broken:
    """A record whose fields cannot be read: the CSV writer fails half-way."""

    def __getattr__(self, name):
        raise RuntimeError("interrupted")


def test_a_failed_csv_write_leaves_the_previous_file(tmp_path):
    path = tmp_path / "records.csv"
    write_csv(small_run(), path)
    before = path.read_text()
    assert before.splitlines()[0] == "model,quantity,family,label,parameter,kappa,error"
    assert len(before.splitlines()) == 13
    run = small_run()
    run.records.insert(3, _Broken())
    with pytest.raises(RuntimeError):
        write_csv(run, path)
    assert path.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["records.csv"]


def test_the_figure_leaves_the_callers_matplotlib_backend_and_pyplot_alone(tmp_path):
    """A notebook user's backend must survive a report: matplotlib.use("Agg") switched it, pyplot kept figures."""
    script = f"""
import sys, matplotlib
sys.path.insert(0, {str(ROOT)!r})
matplotlib.use("svg")
from tests.stability.test_stability_report import small_run
from symkin.stability.report import write_figure
write_figure(small_run(), {str(tmp_path / 'fig.png')!r})
print(matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules)
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True, cwd=ROOT).stdout
    assert out.split() == ["svg", "False"]
    assert (tmp_path / "fig.png").read_bytes()[:4] == b"\x89PNG"
    write_figure(small_run(), tmp_path / "fig.svg")              # the format follows the suffix
    assert b"<svg" in (tmp_path / "fig.svg").read_bytes()[:400]


def test_skip_leaves_quantities_out_and_an_unknown_name_is_refused(tmp_path, capsys):
    from symkin.cli import main

    csv = tmp_path / "records.csv"
    assert main(["bench", "stability", str(ROOT / "models" / "planar_2r.yaml"), "--only", "fk,jacobian", "--skip",
                 "jacobian", "--samples", "2", "--scale-samples", "1", "--float32-samples", "1", "--no-figure",
                 "--csv", str(csv)]) == 0
    assert {line.split(",")[1] for line in csv.read_text().splitlines()[1:]} == {"fk"}
    assert main(["bench", "stability", str(ROOT / "models" / "planar_2r.yaml"), "--skip", "jacobain"]) == 2
    assert "--skip: no quantity jacobain; choose from" in capsys.readouterr().err

"""``symkin workspace``, ``symkin gci`` and ``symkin bench gci``: reports, figures, exit codes."""

from __future__ import annotations

import re
import subprocess

import mpmath
import numpy as np
import pytest

from conftest import GENERATED_DIR, MODELS_DIR, SYMKIN_CLI
from symkin.analysis.convergence import REFERENCE_RTOL
from symkin.cli import main

ARM_DIR = str(GENERATED_DIR / "planar_2r")
PNG = b"\x89PNG\r\n\x1a\n"


def _number(pattern: str, text: str) -> float:
    match = re.search(pattern, text)
    assert match, (pattern, text)
    return float(match.group(1))


def test_bench_gci_has_help():
    result = subprocess.run(SYMKIN_CLI + ["bench", "gci", "--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert "usage: symkin bench gci" in result.stdout


def test_fig_8_19_is_reproduced_by_the_documented_command(tmp_path, capsys):
    """The README's command: both length combinations of seed Fig. 8.19 in one figure."""
    figure, kappa_map = tmp_path / "fig-8-19.png", tmp_path / "map.png"
    assert main(["workspace", ARM_DIR, "--design", "l1=0.1,l2=0.1", "--design", "l1=0.2,l2=0.2", "--unit", "cm",
                 "-o", str(figure), "--map", str(kappa_map)]) == 0
    out = capsys.readouterr().out
    for path in (figure, kappa_map):
        assert path.read_bytes()[:8] == PNG
        assert path.stat().st_size > 20_000
    areas = [float(a) for a in re.findall(r"area: ([0-9.e-]+) \+- [0-9.e-]+ m\^2 \(qmc, \|det J\|", out)]
    assert areas == pytest.approx([np.pi / 2 * 0.01, np.pi / 2 * 0.04], rel=1e-6)
    assert out.count("singular configurations: 200, of which 200 on the workspace boundary") == 2
    assert "planar_2r (l1 = 20 cm, l2 = 20 cm): 40000 configurations" in out


def test_workspace_of_a_model_file_derives_it_on_the_fly(tmp_path, capsys):
    assert main(["workspace", str(MODELS_DIR / "planar_2r.yaml"), "-n", "400", "--no-figure"]) == 0
    assert "planar_2r (as declared): 400 configurations (grid)" in capsys.readouterr().out
    assert list(tmp_path.iterdir()) == []


def _seed_arm_gci() -> float:
    """GCI of the seed's 2R arm (l1 = l2, 0 <= theta1, theta2 <= 90 deg) with dW = |det J| dq, from its closed form.

    J^T J / l^2 has trace t = 3 + 2 cos(theta2) and determinant sin(theta2)^2, so 1/kappa =
    sqrt((t - r) / (t + r)), r = sqrt(t^2 - 4 sin^2); neither depends on theta1 or on l, and
    |det J| = l^2 sin(theta2) integrates to l^2 over the quarter turn: GCI = int_0^(pi/2) (1/kappa) sin
    d theta2, evaluated by mpmath at 30 digits (0.2233408989620130399...).
    """
    with mpmath.workdps(30):
        def integrand(theta2):
            t, det = 3 + 2 * mpmath.cos(theta2), mpmath.sin(theta2) ** 2
            r = mpmath.sqrt(t * t - 4 * det)
            return mpmath.sqrt((t - r) / (t + r)) * mpmath.sin(theta2)

        return float(mpmath.quad(integrand, [0, mpmath.pi / 2]))


def test_gci_reports_value_error_and_measure(capsys):
    assert main(["gci", ARM_DIR, "--method", "adaptive", "-n", "4096"]) == 0
    out = capsys.readouterr().out
    # the adaptive integrator's 1e-13 target; 13 digits printed
    assert _number(r"GCI = ([0-9.]+)", out) == pytest.approx(_seed_arm_gci(), abs=1e-12)
    assert _number(r"int dW = ([0-9.e-]+)", out) == pytest.approx(np.pi / 2 * 0.01, rel=1e-12)
    assert "dW = |det J| dq" in out


def test_gci_on_the_cartesian_domain_warns_about_deterministic_errors(capsys):
    assert main(["gci", ARM_DIR, "--domain", "cartesian", "--method", "grid", "-n", "4096"]) == 0
    assert "note: the reachability indicator is discontinuous" in capsys.readouterr().out
    assert main(["gci", ARM_DIR, "--domain", "cartesian", "--method", "mc", "-n", "4096", "--seed", "1"]) == 0
    assert "confidence half-width (95 %)" in capsys.readouterr().out


def test_gci_of_a_mixed_task_space_uses_a_characteristic_length(tmp_path, capsys):
    kappa_map = tmp_path / "ur10e.png"
    assert main(["gci", str(GENERATED_DIR / "ur10e"), "--method", "qmc", "-n", "1024", "--seed", "0",
                 "--map", str(kappa_map)]) == 0
    out = capsys.readouterr().out
    assert "characteristic length L = " in out
    assert 0 < _number(r"GCI = ([0-9.]+)", out) < 1
    assert kappa_map.read_bytes()[:8] == PNG


def test_bench_gci_prints_a_table_and_plots_time_against_error(tmp_path, capsys):
    figure = tmp_path / "bench.png"
    assert main(["bench", "gci", ARM_DIR, "--budgets", "256,4096", "--repeats", "1", "-o", str(figure)]) == 0
    out = capsys.readouterr().out
    # the reference is integrated to REFERENCE_RTOL and printed to 14 digits (rounding below it): twice the target
    gci = _seed_arm_gci()
    assert _number(r"GCI reference ([0-9.]+)", out) == pytest.approx(gci, abs=2 * REFERENCE_RTOL * gci)
    rows = [line for line in out.splitlines() if re.match(r"\s+(joint|cartesian)\s.*(yes|NO)$", line)]
    assert len(rows) == 2 * 4 * 2 * 2  # domains x integrators x budgets x backends (numpy and c by default)
    assert "fastest run reaching a relative error of the GCI of:" in out
    assert figure.read_bytes()[:8] == PNG


@pytest.mark.parametrize("arguments, message", [
    (["gci", ARM_DIR, "--set", "l3=1"], "not free parameters"),
    (["gci", ARM_DIR, "--set", "l1"], "is not NAME=VALUE"),
    (["gci", ARM_DIR, "--limit", "theta2=0"], "is not JOINT=LOWER:UPPER"),
    (["gci", ARM_DIR, "--limit", "theta9=0:1"], "no coordinates named"),
    (["gci", str(GENERATED_DIR / "ur10e"), "--domain", "cartesian"], "no inverse kinematics"),
    (["workspace", ARM_DIR, "--limit", "theta1=1:0", "--no-figure"], "LOWER must be smaller than UPPER"),
    (["bench", "gci", ARM_DIR, "--methods", "simpson"], "unknown integrators"),
    # a figure without an image suffix failed in matplotlib after the whole sampling
    (["workspace", ARM_DIR, "-o", "ws"], "'ws' names no image format"),
    (["workspace", ARM_DIR, "--map", "map.pnj"], "end it in one of .png"),
])
def test_bad_arguments_exit_with_code_2(arguments, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(arguments)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_missing_generated_code_exits_with_code_2(tmp_path, capsys):
    assert main(["gci", str(tmp_path)]) == 2
    assert "holds no manifest.json" in capsys.readouterr().err


def test_the_workspace_measure_is_printed_with_its_unit(capsys):
    """Issue 16: 'workspace measure int dW = 0.0157' said nothing of its unit."""
    assert main(["gci", str(GENERATED_DIR / "planar_2r"), "--samples", "256"]) == 0
    assert re.search(r"workspace measure int dW = .* m\^2$", capsys.readouterr().out, re.MULTILINE)
    assert main(["gci", str(GENERATED_DIR / "planar_2r"), "--samples", "256", "--measure", "joint"]) == 0
    out = capsys.readouterr().out
    measure = float(re.search(r"int dW = (\S+)", out).group(1))
    assert re.search(r" rad\^2$", out, re.MULTILINE)
    assert abs(measure - (np.pi / 2) ** 2) < 1e-9  # the joint box
    assert main(["gci", str(GENERATED_DIR / "delta"), "--samples", "256"]) == 0
    assert re.search(r"workspace measure int dW = .* m\^3$", capsys.readouterr().out, re.MULTILINE)

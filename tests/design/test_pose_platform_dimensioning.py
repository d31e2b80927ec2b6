"""Dimensioning a platform that translates and rotates (the example Stewart-Gough platform) over a box of positions
at its home orientation, as ``symkin gci`` rates it.

Oracles independent of the programs' J^-1 D trick (kappa_F of J_h^-1 = J^-1 diag(L I, E^-1)): the numpy code's
twist Jacobian (:class:`symkin.mechanism.reach.ConstantOrientation`, J^-1 inverted by LAPACK) with its position rows
divided by L, rated by ``symkin.numerics.conditioning``; the true GCI by ``symkin.analysis.gci``; the CasADi (IPOPT)
and JAX (SLSQP) programs against each other (tests/backends/test_jax_backend.py).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import symkin
from conftest import GENERATED_DIR
from symkin import design
from symkin.cli import main
from symkin.mechanism import reach
from symkin.numerics import conditioning
from tolerances import CLOSED_FORM, KINEMATICS, STEWART_SCALE, svd

STEWART_DIR = str(GENERATED_DIR / "stewart")
#: A box of platform centres within the start design's reach (legs of 0.20 to 0.32 m, home at z = 0.23 m).
BOX = {"x": (-0.03, 0.03), "y": (-0.03, 0.03), "z": (0.21, 0.25)}
LENGTH = 0.2
BOUNDS = {"r_b": (0.1, 0.4), "r_p": (0.05, 0.2)}


@pytest.fixture(scope="module")
def stewart():
    return symkin.load(STEWART_DIR), symkin.load(STEWART_DIR, "casadi")


def test_the_surrogate_is_the_mean_inverse_frobenius_condition_number_of_the_homogenized_twist_jacobian(stewart):
    numpy_model, casadi_model = stewart
    problem = design.design_problem(numpy_model, "gci", ["r_b", "r_p"], box=BOX, length=LENGTH, bounds=BOUNDS)
    program = design.formulate(problem, casadi_model, numpy_model, nodes=3)
    held = reach.constant_orientation(numpy_model.bind(r_b=0.25, r_p=0.12))
    q = held.ik(program.nodes).joints
    J = conditioning.homogenize(held.jacobian(q, program.nodes), LENGTH, (0, 1, 2))
    expected = conditioning.inverse_frobenius_condition_number(J)
    kappa = 1 / conditioning.inverse_condition_number(J)
    value = float(program.objective([0.25, 0.12], program.x0[program.free_count:]))
    # J^-1 to J (LAPACK's LU) and J^-1 D to its adjugate (CasADi's): each eps kappa n relative
    assert value == pytest.approx(np.mean(expected), rel=(KINEMATICS * STEWART_SCALE + svd(6)) * np.max(kappa))
    assert "at the constant orientation roll, pitch, yaw = 0, 0, 0 deg" in program.description


def test_the_stewart_platform_s_best_joint_radii_for_a_box_improve_its_gci(stewart):
    """The independent GCI (1/kappa from singular values, QMC) improves beyond both estimates' errors and the whole
    box stays reachable (JAX gradients find the same design: tests/backends/test_jax_backend.py)."""
    numpy_model, casadi_model = stewart
    problem = design.design_problem(numpy_model, "gci", ["r_b", "r_p"], box=BOX, length=LENGTH, bounds=BOUNDS)
    solution = design.solve(problem, design.formulate(problem, casadi_model, numpy_model, nodes=3))
    assert solution.success, solution.status
    before, after = (design.evaluate(problem, numpy_model, values, samples=2**10)
                     for values in (solution.start, solution.optimum))
    assert after.gci.value - after.gci.error > before.gci.value + before.gci.error
    assert after.box_reachable == 1.0


def test_the_cli_dimensions_the_stewart_platform_at_a_chosen_orientation(stewart, tmp_path, capsys):
    """IPOPT's answer, written with its figures; the surrogate says how the platform was held and homogenized, and the
    independent rating is symkin gci's at that orientation."""
    out = tmp_path / "stewart"
    assert main(["optimize", STEWART_DIR, "--free", "r_b,r_p", "--bounds", "r_b=0.1:0.4,r_p=0.05:0.2",
                 "--require-box", "x=-0.03:0.03,y=-0.03:0.03,z=0.21:0.25", "--length", str(LENGTH), "--nodes", "3",
                 "--orientation", "0,5deg,0", "-n", "256", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "at the constant orientation roll, pitch, yaw = 0, 5, 0 deg" in printed
    assert "position rows divided by L = 0.2 m" in printed
    result = json.loads((out / "result.json").read_text())
    assert result["required_box"]["orientation"] == pytest.approx([0.0, np.radians(5), 0.0], abs=CLOSED_FORM)
    assert result["evaluation"]["optimum"]["gci"] > result["evaluation"]["start"]["gci"]
    optimum = {name: entry["optimum"] for name, entry in result["parameters"].items()}
    held = reach.constant_orientation(stewart[0].bind(**optimum), (0.0, np.radians(5), 0.0))
    box = tuple(np.array([BOX[axis][side] for axis in "xyz"]) for side in (0, 1))
    rated = symkin.analysis.gci(held, method="qmc", samples=256, seed=0, domain="cartesian",
                                inverse=reach.generated_inverse(held), box=box, length=LENGTH)
    assert result["evaluation"]["optimum"]["gci"] == rated.value.value


@pytest.mark.parametrize("model, arguments, message", [
    ("stewart", ["--free", "r_b", "--length", "0.2"], "give --require-box x=LOWER:UPPER,y=LOWER:UPPER,z=LOWER:UPPER"),
    ("stewart", ["--free", "r_b", "--require-box", "x=-0.03:0.03,y=-0.03:0.03,z=0.21:0.25"],
     "mixes translations and rotations"),
    ("agile_eye", ["--free", "r_p", "--require-box", "roll=-0.1:0.1,pitch=-0.1:0.1,yaw=-0.1:0.1"],
     "no free parameter of the model is"),
    ("delta", ["--free", "a", "--require-box", "x=-0.04:0.04,y=-0.04:0.04,z=-0.19:-0.11", "--orientation", "0,0,0"],
     "--orientation: delta is not a platform that translates and rotates"),
    ("stewart", ["--free", "r_b", "--require-box", "x=-0.03:0.03,y=-0.03:0.03,z=0.21:0.25", "--length", "0.2",
                 "--orientation", "0,90deg,0"], "the singularity of the roll-pitch-yaw angles"),
])
def test_what_a_platform_s_dimensioning_needs_is_said(tmp_path, capsys, model, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["optimize", str(GENERATED_DIR / model), *arguments, "-o", str(tmp_path / "out")])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()

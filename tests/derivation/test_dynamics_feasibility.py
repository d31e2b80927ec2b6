"""A model whose forward dynamics cannot be derived is refused by `check` and `derive` alike (issue 13).

The SCARA below carries a point mass on its last revolute axis: moving q4 moves no mass and no
rotational inertia, so M(q) is singular at every configuration and forward_dynamics (an LDL^T
solve with M) has no expression.  Before, `symkin check` passed it and `symkin derive` died with
a Python traceback (NotImplementedError: cannot convert the SymEngine node NaN).  Now both give
the located error, exit code 2, and derive writes nothing; asking only for quantities that do not
invert M works, and so does the same arm once its last link has an inertia about the axis.
"""

from __future__ import annotations

import subprocess

from conftest import SYMKIN_CLI
from sample_models import SCARA



def _run(*args):
    return subprocess.run(SYMKIN_CLI + list(args), capture_output=True, text=True)


def test_a_mass_matrix_singular_everywhere_is_refused_by_check_and_derive(tmp_path):
    model = tmp_path / "scara.yaml"
    model.write_text(SCARA)
    out = tmp_path / "out"
    for command in (["check", str(model)], ["derive", str(model), "-o", str(out)]):
        run = _run(*command)
        assert run.returncode == 2, run.stderr
        assert "Traceback" not in run.stderr
        assert f"{model}:13:" in run.stderr  # located at the bodies section
        assert "singular at every configuration: moving q4" in run.stderr
        assert "forward_dynamics" in run.stderr
        assert "fix:" in run.stderr
    assert not out.exists()
    assert _run("derive", str(model), "-o", str(out), "--only", "fk,mass_matrix,inverse_dynamics", "-q").returncode == 0


def test_the_same_arm_with_an_inertia_about_the_last_axis_derives(tmp_path):
    model = tmp_path / "scara.yaml"
    model.write_text(SCARA.replace("{link: link4, mass: 0.5}", "{link: link4, mass: 0.5, inertia: {xx: 1e-4, "
                                                              "yy: 1e-4, zz: 2e-4}}"))
    run = _run("derive", str(model), "-o", str(tmp_path / "out"), "-q")
    assert run.returncode == 0, run.stderr


def test_a_model_without_mass_asked_for_forward_dynamics_is_refused(tmp_path):
    model = tmp_path / "massless.yaml"
    text = SCARA[:SCARA.index("bodies:")] + "bodies: []\n" + SCARA[SCARA.index("gravity:"):]
    model.write_text(text)
    run = _run("check", str(model))
    assert run.returncode == 2, run.stderr
    assert "the mass matrix is zero" in run.stderr, run.stderr

"""The Novint Falcon of models/devices/novint_falcon.yaml against libnifalcon's published kinematics, and rated beside
its datasheet (issue 64).

The oracle is libnifalcon's inverse kinematics (github.com/libnifalcon/libnifalcon,
src/kinematic/FalconKinematicStamper.cpp, ``IK``, with the constants of include/falcon/core/FalconGeometry.h),
transcribed below: per leg its theta1 (the arm), theta2 (the shin's direction) and theta3 (the parallelogram's
angle to v), in closed form.  symkin's model knows none of it: its legs are a chain of revolute joints closed by the
generated loop closure.  Checked: the closure vanishes at libnifalcon's angles (mapped to the chain's joints as the
model file's comment says), symkin's Gauss-Newton inverse kinematics lands on them, J = dp/dq of the closure is the
inverse of the finite-difference Jacobian of libnifalcon's theta1(p), and every point of the workspace box the
rating reports has libnifalcon's inverse kinematics with 1/kappa at least the rating's threshold.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from conftest import ROOT
from symkin import load, pipeline
from symkin.cli import main
from symkin.model import model_from_text
from symkin.numerics.conditioning import inverse_condition_number
from symkin.runtime.parallel import closure_velocities, solve_closure
from tolerances import KINEMATICS

MODEL_FILE = ROOT / "models" / "devices" / "novint_falcon.yaml"
SPEC_FILE = ROOT / "models" / "datasheets" / "novint_falcon.yaml"
#: FalconGeometry.h (m, rad)
A, B, C, D, E, F = 0.060, 0.1025, 0.014, 0.01125, 0.01125, -0.025
R, S = 0.037233758, -0.027330909
PHY = (np.pi / 2 + np.pi / 12, -np.pi / 6 + np.pi / 12, -5 * np.pi / 6 + np.pi / 12)
#: Poses in libnifalcon's frame (m): the model's home, and two off the axis in the workspace of its cube test.
POSES = np.array([[0.0, 0.0, 0.125], [0.03, -0.02, 0.10], [-0.02, 0.04, 0.15]])


def libnifalcon_ik(p: np.ndarray) -> np.ndarray:
    """(theta1, theta2, theta3) of each leg, (3, 3), as FalconKinematicStamper::IK computes them (NaN unreached)."""
    out = []
    for phy in PHY:
        pu = -R + np.cos(phy) * p[0] + np.sin(phy) * p[1]
        pv = -(S - np.cos(phy) * p[1] + np.sin(phy) * p[0])
        pw = p[2]
        theta3 = np.arccos((pv + F) / B)
        sin3 = np.sin(theta3)
        common = (pw ** 2 + pu ** 2 + 2 * C * pu + A ** 2 + C ** 2 - D ** 2 - E ** 2 - B ** 2 * sin3 ** 2
                  - 2 * B * E * sin3 - 2 * B * D * sin3 - 2 * D * E)
        l0, l1, l2 = common - 2 * A * pu - 2 * A * C, -4 * A * pw, common + 2 * A * pu + 2 * A * C
        theta1 = 2 * np.arctan((-l1 - np.sqrt(l1 * l1 - 4 * l0 * l2)) / (2 * l2))
        theta2 = np.arccos((-pu + A * np.cos(theta1) - C) / (-D - E - B * sin3))
        out.append((theta1, theta2, theta3))
    return np.array(out)


def chain_joints(angles: np.ndarray) -> np.ndarray:
    """The model's passive joints (knee, swing, sway, ankle per leg) at libnifalcon's angles."""
    return np.concatenate([[t2 - t1, np.pi / 2 - t3, t3 - np.pi / 2, -t2] for t1, t2, t3 in angles])


def arm_jacobian(p: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """d theta1 / dp of libnifalcon's ik by central differences (error O(step^2) + O(eps / step))."""
    return np.column_stack([(libnifalcon_ik(p + step * e)[:, 0] - libnifalcon_ik(p - step * e)[:, 0]) / (2 * step)
                            for e in np.eye(3)])


@pytest.fixture(scope="module")
def falcon(tmp_path_factory):
    model = model_from_text(MODEL_FILE.read_text(), file=str(MODEL_FILE))
    request = pipeline.resolve_request(model, "closure,closure_jacobians", fixed="all")
    return load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("falcon")))


def test_the_closure_vanishes_at_libnifalcons_inverse_kinematics(falcon):
    for p in POSES:
        angles = libnifalcon_ik(p)
        residual = falcon.closure(angles[:, 0], chain_joints(angles), p)
        assert np.max(np.abs(residual)) <= KINEMATICS * 0.2      # lengths of about 0.2 m, angles of about 1 rad


def test_symkins_inverse_kinematics_lands_on_libnifalcons_angles(falcon):
    home = libnifalcon_ik(POSES[0])
    q, s = home[:, 0], chain_joints(home)
    for p in POSES[1:]:
        report = solve_closure(falcon, q, s, p, unknowns=("q", "s"))
        assert bool(np.all(report.converged))
        np.testing.assert_allclose(report.solution["q"], libnifalcon_ik(p)[:, 0], rtol=0, atol=1e-10)


def test_the_closures_jacobian_inverts_libnifalcons_arm_rates(falcon):
    for p in POSES:
        angles = libnifalcon_ik(p)
        J = closure_velocities(falcon, angles[:, 0], chain_joints(angles), p).J
        # the finite difference's error: step^2 |theta'''| + eps |theta| / step, about 1e-10 of |dtheta/dp|
        np.testing.assert_allclose(J @ arm_jacobian(p), np.eye(3), rtol=0, atol=1e-7)


def test_the_falcon_is_rated_beside_its_datasheet_and_its_box_is_usable(tmp_path):
    out = tmp_path / "rate"
    assert main(["rate", str(MODEL_FILE), "--encoder", "1280", "--gear", "7.719", "--effort-limit", "1", "-n", "512",
                 "--no-figure", "--datasheet", str(SPEC_FILE), "-o", str(out)]) == 0
    record = json.loads((out / "datasheet.json").read_text())
    maker = {figure["measure"]: figure for figure in record["maker"]["figures"]}
    assert set(maker) == {"force_x", "resolution_x"}
    # the nominal resolution along x: one encoder count, 2 pi / (1280 * 7.719) rad, of the arm that moves x most
    step = 2 * np.pi / (1280 * 7.719)
    J = np.linalg.inv(arm_jacobian(POSES[0]))
    assert maker["resolution_x"]["symkin"] == pytest.approx(step * np.max(np.abs(J[0])), rel=1e-6)
    # the force along x from 1 N m at each arm: the largest f with |J^T f e_x| <= 1
    assert maker["force_x"]["symkin"] == pytest.approx(1 / np.max(np.abs(J[0])), rel=1e-6)
    # as docs/analysis.md quotes them: 39 um, 16.5 N per N m (8.9 N asks 0.54 N m), the box 94 x 117 x 47 mm
    assert round(1e6 * maker["resolution_x"]["symkin"]) == 39
    assert (round(maker["force_x"]["symkin"], 1), round(8.9 / maker["force_x"]["symkin"], 2)) == (16.5, 0.54)
    assert [round(1e3 * size) for size in record["workspace_shapes"]["box"]["size_m"]] == [94, 117, 47]
    assert record["maker"]["workspace_box"]["fits"] is False
    box = record["workspace_shapes"]["box"]
    points = np.random.default_rng(64).uniform(box["lower_m"], box["upper_m"], (300, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        reached = [np.isfinite(libnifalcon_ik(p)).all() for p in points]
    assert all(reached)
    conditioning = [inverse_condition_number(arm_jacobian(p)) for p in points]
    assert min(conditioning) >= 0.05


def test_with_the_jax_backend_the_falcon_is_rated_by_the_numpy_code_and_says_so(tmp_path, capsys):
    """Legs without closed forms are continued point by point on the host, where JAX's dispatch per call made the GCI
    30 times slower: --backend jax takes the numpy code and says so.  Without effort limits, masses or encoders no
    measure is mapped: the datasheet says so instead of drawing an empty figure (a ZeroDivisionError before)."""
    out = tmp_path / "rate"
    assert main(["rate", str(MODEL_FILE), "--backend", "jax", "-n", "128", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "--backend jax: its legs have no closed forms, so the loop closure is continued point by point on the " \
           "host, with the numpy code" in printed
    assert "no datasheet.png: no measure over every direction was rated" in printed
    assert sorted(path.name for path in out.iterdir()) == ["datasheet.csv", "datasheet.json", "summary.txt"]


def test_only_continued_legs_asked_for_with_jax_get_the_numpy_code(falcon, capsys):
    """The choice is read from the manifest before any code is loaded (no JAX import here: a JAX load that keeps its
    code is tests/backends/test_jax_backend.py's); asked for with numpy, the same legs keep it and print nothing."""
    from symkin.analysis.model_files import load_for_analysis
    from symkin.cli.analysis_args import say_where_continued

    taken = load_for_analysis(str(falcon.directory), "jax")
    assert (taken.name, taken.backend) == ("novint_falcon", "numpy")
    say_where_continued("jax", taken)
    assert "novint_falcon: --backend jax: its legs have no closed forms" in capsys.readouterr().out
    kept = load_for_analysis(str(falcon.directory), "numpy")    # the same legs asked for with the host's code
    say_where_continued("numpy", kept)
    assert kept.backend == "numpy"
    assert capsys.readouterr().out == ""

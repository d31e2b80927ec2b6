"""Passive-joint limits of a parallel mechanism in the workspace and GCI analyses (issue 6).

The model is the example DELTA written leg by leg (and, once, by the shorthand's
``elbow_limits``), with limits on the elbow U joints' second angle (the parallelogram's sideways swing).  It
is derived once; the limit variants are made by editing the manifest record the analyses
read (``model.parallel.legs[i].passive_limits``), as a model file with those limits would
write it.  Oracles: the generated closure itself (residual), the closed-form passive
angles of a DELTA leg (below), and the shorthand DELTA without limits (exact equality).
"""

from __future__ import annotations

import copy
import re
import warnings
from unittest import mock

import numpy as np
import pytest

import symkin
from symkin.mechanism import feasibility
from symkin.numerics import sampling
from symkin.analysis import global_indices
from symkin.mechanism import reach
from symkin.mechanism.working_mode import working_mode
from symkin import mechanism
from symkin.mechanism import passive
from symkin.mechanism.limits import wrap_angle
from symkin.runtime.loader import LoadedModel

from conftest import GENERATED_DIR, MODELS_DIR
from tolerances import CLOSED_FORM

DELTA = symkin.load(str(GENERATED_DIR / "delta"))
LEG_ANGLES = np.radians([0.0, 120.0, 240.0])

MODEL = """name: delta_legs
parameters:
  r_base: {value: 0.07, unit: m}
  r_tcp: {value: 0.025, unit: m}
  a: {value: 0.1, unit: m}
  b: {value: 0.15, unit: m}
parallel:
  motion: translation
  chains:
    ruu:
      - {name: theta, type: R, axis: [0, -1, 0], active: true, limits: [deg(-90), deg(60)]}
      - {name: elbow, type: U, axes: [[0, -1, 0], [0, 0, 1]], origin: {xyz: [a, 0, 0]}, limits: [null, [deg(-20), deg(20)]]}
      - {name: wrist, type: U, axes: [[0, 0, 1], [0, -1, 0]], origin: {xyz: [b, 0, 0]}}
  legs:
    - {chain: ruu, base: {radius: r_base, angle: 0}, platform: {radius: r_tcp, angle: 0}, ik_branch: negative}
    - {chain: ruu, base: {radius: r_base, angle: deg(120)}, platform: {radius: r_tcp, angle: deg(120)}, ik_branch: negative}
    - {chain: ruu, base: {radius: r_base, angle: deg(240)}, platform: {radius: r_tcp, angle: deg(240)}, ik_branch: negative}
  home: [0, 0, -0.15]
scene:
  outputs: [ik, fk, jacobian, closure, closure_jacobians]
  backends: [numpy]
"""


@pytest.fixture(scope="module")
def limited(tmp_path_factory):
    """The leg-by-leg DELTA with elbow limits of +-20 deg, derived once."""
    path = tmp_path_factory.mktemp("passive") / "delta_legs.yaml"
    path.write_text(MODEL)
    return symkin.load(symkin.derive(path, path.parent / "generated"))


def _variant(model: LoadedModel, limits: dict[str, list[float]] | None) -> LoadedModel:
    """The model with every leg's passive limits replaced by ``limits`` (names without the leg number)."""
    manifest = copy.deepcopy(model.manifest)
    for n, leg in enumerate(manifest["model"]["parallel"]["legs"], start=1):
        leg.pop("passive_limits", None)
        if limits:
            leg["passive_limits"] = {name.replace("#", str(n)): bounds for name, bounds in limits.items()}
    return LoadedModel(model.directory, manifest, "numpy", model._raw)


def _elbow(width_deg: float) -> dict[str, list[float]]:
    return {"elbow#_2": [-np.radians(width_deg), np.radians(width_deg)]}


def _closed_form(q: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Passive angles of the DELTA legs in closed form, (N, 12), in the order of s.

    The rod direction in leg i's axes, d = Rz(-phi_i)(B_i - C_i) / b, equals
    Ry(-alpha) Rz(u2) e_x = (cos u2 cos alpha, sin u2, cos u2 sin alpha) with alpha = theta + u1
    (elbow U: about -y, then z); the wrist U (z, then -y) undoes the rotation:
    w1 = -u2, w2 = -alpha.  Branch: cos u2 > 0.
    """
    P = DELTA.parameters
    columns = []
    for i, phi in enumerate(LEG_ANGLES):
        theta = q[:, i]
        cos_phi, sin_phi = np.cos(phi), np.sin(phi)
        b_point = p + P["r_tcp"] * np.array([cos_phi, sin_phi, 0.0])
        c_point = np.stack([(P["r_base"] + P["a"] * np.cos(theta)) * cos_phi,
                            (P["r_base"] + P["a"] * np.cos(theta)) * sin_phi, P["a"] * np.sin(theta)], axis=-1)
        v = (b_point - c_point) / P["b"]
        d = np.stack([cos_phi * v[:, 0] + sin_phi * v[:, 1], -sin_phi * v[:, 0] + cos_phi * v[:, 1], v[:, 2]], axis=-1)
        u2 = np.arcsin(d[:, 1])
        alpha = np.arctan2(d[:, 2], d[:, 0])
        columns += [alpha - theta, u2, -u2, -alpha]
    return np.stack(columns, axis=-1)


@pytest.fixture(scope="module")
def poses():
    """The working-mode configurations of a joint grid over the actuator limits (the whole
    workspace, edges included), their TCP positions and closed-form passive angles."""
    box = mechanism.joint_limits(DELTA)
    q = sampling.grid(box[:, 0], box[:, 1], 12, midpoints=False)
    p, inside = working_mode(DELTA, q)
    return q[inside], p[inside], _closed_form(q[inside], p[inside])


def test_passive_variables_close_the_loop_on_the_home_branch(limited, poses):
    q, p, expected = poses
    assert len(q) > 1000
    model = _variant(limited, _elbow(180))
    solution = passive.solve_passive(model, passive.declared_limits(model), q, p)
    assert solution.resolved.all()
    assert np.max(np.abs(model.closure(q, solution.s, p))) <= 1e-10
    assert np.max(np.abs(wrap_angle(solution.s - expected))) < 1e-9
    # elbow_2 is reported in its declared interval [-pi, pi]
    assert np.all(np.abs(solution.s[:, [1, 5, 9]]) <= np.pi)


def test_a_pose_beyond_a_passive_limit_is_excluded_one_inside_kept(limited, poses):
    q, p, expected = poses
    swing = np.degrees(np.max(np.abs(expected[:, [1, 5, 9]]), axis=1))
    inside, beyond = np.argmin(np.abs(swing - 15)), np.argmin(np.abs(swing - 25))
    assert abs(swing[inside] - 15) < 2
    assert abs(swing[beyond] - 25) < 2
    ik = reach.generated_inverse(limited)  # +-20 deg
    points = p[[inside, beyond]]
    _, valid = ik.solve(points)
    assert valid[:, 0].tolist() == [True, False]
    _, in_mode = working_mode(limited, q[[inside, beyond]])
    assert in_mode.tolist() == [True, False]
    # without the limits both are in the workspace
    assert reach.generated_inverse(_variant(limited, None)).solve(points)[1][:, 0].all()


def test_tighter_passive_limits_shrink_the_workspace(limited):
    ik = reach.generated_inverse(DELTA)
    lower, upper = np.array([-0.13, -0.13, -0.27]), np.array([0.13, 0.13, -0.05])
    axes = [np.linspace(lo, hi, 14) for lo, hi in zip(lower, upper)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    box = mechanism.joint_limits(DELTA)
    revolute = mechanism.revolute_mask(DELTA)
    previous = feasibility.reachable(ik, points, box, revolute)
    counts = [int(previous.sum())]
    for width in (90, 30, 20, 10):
        model = _variant(limited, _elbow(width))
        current = feasibility.reachable(reach.generated_inverse(model), points, box, revolute)
        assert not np.any(current & ~previous)  # a subset of the looser limits' workspace
        counts.append(int(current.sum()))
        previous = current
    assert counts[0] == counts[1] > counts[2] > counts[3] > counts[4] > 0, counts
    volumes = [global_indices.workspace_measure(_variant(limited, _elbow(w)), method="grid", samples=1000).value
               for w in (30, 20, 10)]
    assert volumes[0] > volumes[1] > volumes[2] > 0, volumes


def test_wide_passive_limits_reproduce_the_unlimited_analyses_exactly(limited):
    wide = _variant(limited, {"elbow#_1": [-np.pi, np.pi], "elbow#_2": [-np.pi / 2, np.pi / 2],
                              "wrist#_1": [-4.0, 4.0], "wrist#_2": [-np.pi, np.pi]})
    with warnings.catch_warnings():
        warnings.simplefilter("error", passive.PassiveJointWarning)
        box = reach.bounding_box(DELTA)
        for domain in ("joint", "cartesian"):
            expected = global_indices.gci(DELTA, method="grid", samples=1500, domain=domain, box=box,
                                          inverse=reach.generated_inverse(DELTA))
            result = global_indices.gci(wide, method="grid", samples=1500, domain=domain, box=box,
                                        inverse=reach.generated_inverse(wide))
            assert (result.value.value, result.measure.value) == (expected.value.value, expected.measure.value)
            assert (result.value.error, result.measure.error) == (expected.value.error, expected.measure.error)


def test_unresolved_passive_variables_are_unreachable_and_reported(limited, poses):
    q, p, _ = poses
    limits = passive.declared_limits(limited)
    candidates = np.ones(4, dtype=bool)
    with pytest.warns(passive.PassiveJointWarning, match="2 of 4 assembled poses"):
        ok = passive.admissible(limited, limits, q[:4], np.concatenate([p[:2], p[2:4] + 0.01]), candidates)
    assert not ok[2:].any()


@pytest.mark.parametrize("limits, message", [
    ({"elbow#_2": [0.5, -0.5]}, r"legs\[0\]\.passive_limits\.elbow1_2: expected \[lower, upper\]"),
    ({"elbow#_2": [0.5]}, "expected"),
    ({"elbow#_2": [-np.inf, 0.5]}, "finite"),
    ({"knee#": [-1.0, 1.0]}, "no passive joint variable of that name"),
])
def test_malformed_passive_limits_are_refused_with_their_place(limited, limits, message):
    model = _variant(limited, limits)
    with pytest.raises(ValueError, match=message):
        reach.generated_inverse(model)
    with pytest.raises(ValueError, match=message):
        global_indices.gci(model, method="grid", samples=200)


def test_a_model_file_with_passive_limits_is_analysed_on_the_fly(tmp_path, capsys):
    """The CLI derives the loop closure of a model file that limits passive joints (+-20 deg here)."""
    from symkin.cli import main

    path = tmp_path / "delta_legs.yaml"
    path.write_text(MODEL.replace("  outputs: [ik, fk, jacobian, closure, closure_jacobians]\n", "  outputs: [ik]\n"))
    assert main(["gci", str(path), "--method", "grid", "-n", "1000"]) == 0
    measure = float(re.search(r"int dW = ([0-9.e-]+)", capsys.readouterr().out).group(1))
    unlimited = global_indices.workspace_measure(DELTA, method="grid", samples=1000).value
    assert 0.1 * unlimited < measure < 0.6 * unlimited


def test_least_squares_steps_agree_with_pinv_also_where_rank_deficient():
    from symkin import newton

    rng = np.random.default_rng(3)
    A = rng.normal(size=(6, 18, 12))
    A[2, :, 5] = A[2, :, 4]  # rank 11: the minimum-norm step
    A[4, :, 7] = 0.0
    r = rng.normal(size=(6, 18))
    expected = -np.einsum("kij,kj->ki", np.linalg.pinv(A), r)
    # one batch mixes both paths: QR for the full-rank matrices, pinv for the others
    with mock.patch("symkin.newton._pinv_steps", wraps=newton._pinv_steps) as pinv:
        np.testing.assert_allclose(newton.least_squares_steps(A, r), expected, rtol=1e-9, atol=1e-12)
    (call,) = pinv.call_args_list
    assert len(call.args[0]) == 2
    np.testing.assert_allclose(newton.least_squares_steps(A[[0, 1, 3]], r[[0, 1, 3]]), expected[[0, 1, 3]], rtol=1e-9)


def test_left_inverses_are_the_pseudo_inverses_also_where_rank_deficient():
    """R^-1 Q^T where A has full column rank, the SVD's pseudo-inverse of the two rank-deficient matrices; a wide
    batch takes the pseudo-inverse throughout."""
    from symkin import newton

    rng = np.random.default_rng(4)
    A = rng.normal(size=(6, 18, 12))
    A[2, :, 5] = A[2, :, 4]
    A[4, :, 7] = 0.0
    expected = np.linalg.pinv(A)
    got = newton.left_inverses(A)
    for k in (0, 1, 3, 5):      # QR and the SVD: rounding amplified by cond(A)
        bound = 64 * np.finfo(float).eps * np.linalg.cond(A[k]) * np.abs(expected[k]).max()
        np.testing.assert_allclose(got[k], expected[k], rtol=0, atol=bound)
    np.testing.assert_allclose(got[[2, 4]], expected[[2, 4]], rtol=0, atol=1e-12)   # the SVD's, both ways
    wide = np.swapaxes(A[:2], 1, 2)
    np.testing.assert_array_equal(newton.left_inverses(wide), np.linalg.pinv(wide))

def test_joint_and_cartesian_domains_agree_under_passive_limits(limited):
    """Two formulations of the limited workspace: |det J| dq over the configurations within the
    passive limits (fk, then s) and the reachability indicator over a box (ik, then s)."""
    joint = global_indices.workspace_measure(limited, method="grid", samples=8000)
    cartesian = global_indices.workspace_measure(limited, method="grid", samples=8000, domain="cartesian",
                                                 box=reach.bounding_box(DELTA),
                                                 inverse=reach.generated_inverse(limited))
    assert abs(joint.value - cartesian.value) <= min(joint.error + cartesian.error, 0.05 * cartesian.value)
    assert cartesian.value < 0.5 * global_indices.workspace_measure(DELTA, method="grid", samples=8000).value


def test_the_delta_shorthand_declares_the_same_passive_limits(limited, tmp_path):
    """``elbow_limits`` of the shorthand = ``limits`` on the leg-by-leg elbow U joints."""
    text = (MODELS_DIR / "delta.yaml").read_text()
    text = text.replace("actuator_limits: [deg(-90), deg(60)]",
                        "actuator_limits: [deg(-90), deg(60)]\n    elbow_limits: [null, [deg(-20), deg(20)]]")
    text = re.sub(r"scene:.*", "scene:\n  outputs: [ik, fk, jacobian, closure, closure_jacobians]\n"
                  "  backends: [numpy]\n", text, flags=re.S)
    path = tmp_path / "delta.yaml"
    path.write_text(text)
    shorthand = symkin.load(symkin.derive(path, tmp_path / "generated"))
    records = [leg.get("passive_limits") for leg in shorthand.manifest["model"]["parallel"]["legs"]]
    assert records == [leg.get("passive_limits") for leg in limited.manifest["model"]["parallel"]["legs"]]
    # the manifest's 20 pi / 180 is rounded once, numpy's radians twice
    assert records[0] == {"elbow1_2": pytest.approx([-np.radians(20), np.radians(20)], rel=CLOSED_FORM)}
    box = mechanism.joint_limits(DELTA)
    q = sampling.grid(box[:, 0], box[:, 1], 8, midpoints=False)
    assert np.array_equal(working_mode(shorthand, q)[1], working_mode(limited, q)[1])
    assert not working_mode(shorthand, q)[1].all()


@pytest.mark.parametrize("value, message", [
    ("[[deg(-20), deg(20)]]", "write exactly 2 limits"),
    ("[null, [deg(20), deg(-20)]]", "lower"),
    ("deg(20)", "write a YAML list of limits"),
])
def test_malformed_delta_passive_limits_name_their_place(tmp_path, value, message):
    text = (MODELS_DIR / "delta.yaml").read_text().replace(
        "actuator_limits: [deg(-90), deg(60)]", f"actuator_limits: [deg(-90), deg(60)]\n    wrist_limits: {value}")
    path = tmp_path / "delta.yaml"
    path.write_text(text)
    from symkin.errors import ModelError

    with pytest.raises(ModelError, match=r"parallel\.delta\.wrist_limits") as error:
        symkin.derive(path, tmp_path / "out")
    assert message in str(error.value)
    assert not (tmp_path / "out").exists()

"""Parallel mechanisms in the model format: legs, the DELTA shorthand, located errors, the coordinates,
serial/parallel quantities, and new topologies that need nothing but a model file."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
import sympy

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import load, pipeline
from symkin.derivation import Derivation, emitted_quantities
from symkin.errors import DerivationError, ModelError
from symkin.model import model_from_text
from symkin.model.schema import Translation
from symkin.runtime.parallel import solve_closure, solve_fk
from symkin.structure.mobility import model_mobility
from tolerances import DELTA_SCALE, EPS, KINEMATICS, NEWTON

DELTA = textwrap.dedent("""\
    name: d
    parameters:
      rb: 0.1
      rp: 0.03
      la: 0.1
      lb: 0.2
    parallel:
      delta:
        base: {joint_at: vertex, radius: rb}
        platform: {joint_at: vertex, radius: rp}
        upper_arm: la
        lower_arm: lb
        leg_angles: [0, deg(120), deg(240)]
    """)

LINEAR_DELTA = textwrap.dedent("""\
    # 3-PUU: a linear DELTA, carriages on vertical rails at the base (seed sec. 2.2.2, 'PUU').
    name: linear_delta
    parameters: {R: 0.15, r: 0.03, L: 0.2}
    parallel:
      motion: translation
      chains:
        puu:
          - {name: s, type: P, axis: [0, 0, 1], active: true}
          - {name: c, type: U, axes: [[0, 1, 0], [0, 0, 1]]}
          - {name: w, type: U, axes: [[0, 0, 1], [0, 1, 0]], origin: {xyz: [L, 0, 0]}}
      legs:
        - {chain: puu, base: {radius: R, angle: 0}, platform: {radius: r, angle: 0}}
        - {chain: puu, base: {radius: R, angle: deg(120)}, platform: {radius: r, angle: deg(120)}}
        - {chain: puu, base: {radius: R, angle: deg(240)}, platform: {radius: r, angle: deg(240)}}
      home: [0, 0, -0.1]
    scene: {outputs: [ik, fk, jacobian, singularities, constraints, constraint_jacobians]}
    """)

TSAI_UPU = textwrap.dedent("""\
    # 3-UPU translational platform (Tsai), struts of variable length (seed sec. 2.2.2, 'UPU').
    name: upu
    parameters: {R: 0.15, r: 0.05}
    parallel:
      motion: translation
      chains:
        upu:
          - {name: ub, type: U}
          - {name: l, type: P, axis: [1, 0, 0], active: true}
          - {name: up, type: U}
      legs:
        - {chain: upu, base: {radius: R, angle: 0}, platform: {radius: r, angle: 0}}
        - {chain: upu, base: {radius: R, angle: deg(120)}, platform: {radius: r, angle: deg(120)}}
        - {chain: upu, base: {radius: R, angle: deg(240)}, platform: {radius: r, angle: deg(240)}}
      home: [0, 0, -0.2]
    scene: {outputs: [ik, fk, jacobian, constraints, constraint_jacobians]}
    """)

CUR = textwrap.dedent("""\
    name: cur
    parallel:
      motion: translation
      chains:
        cur:
          - {name: c, type: C, axis: [0, 0, 1], active: true}
          - {name: u, type: U, origin: {xyz: [0.1, 0, 0]}, axes: [[0, 0, 1], [0, 1, 0]]}
          - {name: r, type: R, origin: {xyz: [0.1, 0, 0]}, axis: [0, 1, 0]}
      legs:
        - {chain: cur, base: {radius: 0.2, angle: 0}, platform: {radius: 0.05, angle: 0}}
        - {chain: cur, base: {radius: 0.2, angle: deg(120)}, platform: {radius: 0.05, angle: deg(120)}}
        - {chain: cur, base: {radius: 0.2, angle: deg(240)}, platform: {radius: 0.05, angle: deg(240)}}
    """)


def _derive(text, tmp_path):
    model = model_from_text(text)
    out = pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), tmp_path)
    return model, load(out)


# --------------------------------------------------------------------------- the format

@pytest.mark.parametrize("spec, radius", [
    ("{joint_at: vertex, radius: rb}", "rb"),
    ("{joint_at: side_midpoint, radius: rb}", "rb/2"),
    ("{joint_at: vertex, side: rb}", "rb/sqrt(3)"),
    ("{joint_at: side_midpoint, side: rb}", "rb/(2*sqrt(3))"),
])
def test_delta_radius_convention_is_explicit(spec, radius):
    model = model_from_text(DELTA.replace("{joint_at: vertex, radius: rb}", spec))
    rb = model.parameter("rb").symbol
    for leg in model.parallel.legs:
        translation = next(op for op in leg.base if isinstance(op, Translation))
        assert sympy.simplify(translation.vector[0] - sympy.sympify(radius, locals={"rb": rb})) == 0


def test_coordinates_of_parallel_models(models):
    delta, stewart = models["delta"], models["stewart"]
    assert [c.name for c in delta.coordinates] == ["theta1", "theta2", "theta3"]
    assert delta.task_space == ("x", "y", "z")
    assert delta.dof == 3
    assert delta.joints == ()
    assert [c.type.value for c in stewart.coordinates] == ["P"] * 6
    assert stewart.task_space == ("x", "y", "z", "roll", "pitch", "yaw")
    assert delta.mechanism == "parallel"
    assert models["ur10e"].mechanism == "serial"


BAD = [
    ("no joint_at", "{joint_at: vertex, radius: rb}", "{radius: rb}", "parallel.delta.base",
     "missing required key 'joint_at'"),
    ("unknown joint_at", "joint_at: vertex, radius: rb}", "joint_at: corner, radius: rb}", "parallel.delta.base.joint_at",
     "unknown joint position 'corner'"),
    ("radius and side", "{joint_at: vertex, radius: rb}", "{joint_at: vertex, radius: rb, side: rb}",
     "parallel.delta.base", "exactly one of 'radius:'"),
    ("negative arm", "upper_arm: la", "upper_arm: -la", "parallel.delta.upper_arm", "must be positive"),
    ("two angles", "leg_angles: [0, deg(120), deg(240)]", "leg_angles: [0, deg(120)]", "parallel.delta.leg_angles",
     "expected 3 leg angles"),
    ("coinciding legs", "leg_angles: [0, deg(120), deg(240)]", "leg_angles: [0, 0, deg(240)]",
     "parallel.delta.leg_angles", "coincide"),
    ("clash with a task coordinate", "  rb: 0.1\n", "  rb: 0.1\n  z: 0.3\n", "parameters.z",
     "clashes with the task coordinate 'z'"),
    ("clash with a passive joint", "  rb: 0.1\n", "  rb: 0.1\n  elbow1_2: 0.3\n", "parameters.elbow1_2",
     "clashes with the symbol 'elbow1_2' of joint 'elbow1'"),
    ("task space", "parallel:\n", "task_space: [x, y]\nparallel:\n", "task_space", "follows from 'parallel.motion'"),
    ("serial and parallel", "parallel:\n", "serial: {chain: [{name: q1}]}\nparallel:\n", "", "both a serial chain"),
]


@pytest.mark.parametrize("case, old, new, key, message", BAD, ids=[c[0] for c in BAD])
def test_bad_delta_models_give_located_errors(case, old, new, key, message):
    assert old in DELTA
    with pytest.raises(ModelError) as err:
        model_from_text(DELTA.replace(old, new, 1), file="bad.yaml")
    problems = [p for p in err.value.problems if message in p.message]
    assert problems, str(err.value)
    assert problems[0].key == key
    assert problems[0].file == "bad.yaml"
    assert problems[0].fix


BAD_LEGS = [
    ("active spherical joint", "- {name: up, type: U}", "- {name: up, type: S, active: true}", "chains.upu[2].active",
     "cannot be actuated"),
    ("too many actuators", "- {name: ub, type: U}", "- {name: ub, type: R, axis: [0, 0, 1], active: true}", "parallel",
     "have 6 active joints"),
    ("unknown joint type", "- {name: up, type: U}", "- {name: up, type: Q}", "chains.upu[2].type",
     "unknown joint type 'Q'"),
    ("parallel U axes", "- {name: ub, type: U}", "- {name: ub, type: U, axes: [[0, 0, 1], [0, 0, -1]]}",
     "chains.upu[0].axes", "parallel"),
    ("axis on a U joint", "- {name: ub, type: U}", "- {name: ub, type: U, axis: [0, 0, 1]}", "chains.upu[0].axis",
     "takes 'axes'"),
    ("offset of a passive joint", "- {name: up, type: U}", "- {name: up, type: U, offset: 0.1}",
     "chains.upu[2].offset", "applies to the actuated variable"),
    ("unknown chain", "- {chain: upu, base: {radius: R, angle: 0}", "- {chain: upx, base: {radius: R, angle: 0}",
     "parallel.legs[0].chain", "unknown chain 'upx'"),
    ("unknown motion", "motion: translation", "motion: rotation", "parallel.motion", "unknown platform motion"),
    ("home of the wrong size", "home: [0, 0, -0.2]", "home: [0, 0]", "parallel.home", "expected 3 task coordinates"),
    ("unknown branch", "home: [0, 0, -0.2]", "fk_branch: up", "parallel.fk_branch", "unknown branch 'up'"),
    ("bodies as a serial list", "scene:", "bodies: [{link: l1, mass: 1}]\nscene:", "bodies", "expected a mapping"),
    ("unknown body", "scene:", "bodies: {arm: {mass: 1}}\nscene:", "bodies.arm", "unknown key 'arm'"),
    ("negative rod mass", "scene:", "bodies: {rod: {mass: -1}}\nscene:", "bodies.rod.mass", "negative mass"),
    ("rod fraction above one", "scene:", "bodies: {rod: {mass: 1, platform_fraction: 2}}\nscene:",
     "bodies.rod.platform_fraction", "fraction of the rod mass"),
]


@pytest.mark.parametrize("case, old, new, key, message", BAD_LEGS, ids=[c[0] for c in BAD_LEGS])
def test_bad_leg_models_give_located_errors(case, old, new, key, message):
    assert old in TSAI_UPU
    with pytest.raises(ModelError) as err:
        model_from_text(TSAI_UPU.replace(old, new, 1), file="legs.yaml")
    problems = [p for p in err.value.problems if message in p.message]
    assert problems, str(err.value)
    assert problems[0].key.endswith(key)
    assert problems[0].line is not None


def test_bad_parallel_model_on_the_command_line_exits_2(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(DELTA.replace("joint_at: vertex, radius: rb}", "joint_at: corner, radius: rb}", 1))
    result = subprocess.run(SYMKIN_CLI + ["derive", str(path), "-o", str(tmp_path / "out")], capture_output=True,
                            text=True)
    assert result.returncode == 2
    assert "bad.yaml:9:" in result.stderr
    assert "unknown joint position 'corner'" in result.stderr
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- quantities

def test_serial_quantities_on_a_parallel_model_and_vice_versa(models):
    with pytest.raises(DerivationError, match="'frames' is derived for serial mechanisms, but model 'delta' is a "
                                              "parallel mechanism; its outputs are: .*ik"):
        Derivation(models["delta"])["frames"]
    with pytest.raises(DerivationError, match="'ik' is derived for parallel mechanisms, but model 'ur10e'"):
        Derivation(models["ur10e"]).functions(["ik"])
    with pytest.raises(DerivationError, match="'jacobian_geometric' is derived for serial"):
        Derivation(models["stewart"]).functions(["jacobian_geometric"])
    # fk and jacobian exist for both kinds, derived differently.
    assert Derivation(models["delta"])["fk"].outputs[0].name == "position"
    assert Derivation(models["ur10e"])["fk"].outputs[0].name == "base_T_tcp"
    assert "ik" in emitted_quantities("parallel")
    assert "ik" not in emitted_quantities("serial")
    assert "frames" in emitted_quantities()
    assert "closure" in emitted_quantities()
    with pytest.raises(ModelError, match="unknown output 'frames'"):
        pipeline.resolve_request(models["delta"], "frames")


def test_no_closed_form_fk_for_a_stewart_platform(models):
    with pytest.raises(DerivationError, match="translational platform on three legs.*solve_fk"):
        Derivation(models["stewart"])["fk"]


def test_a_leg_without_distance_form_still_has_its_loop_closure():
    model = model_from_text(CUR)
    d = Derivation(model)
    with pytest.raises(DerivationError, match="leg 'leg1' has no distance form: its last joint r1 is a R joint.*"
                                              "closure and closure_jacobians"):
        d["ik"]
    spec = d["closure_jacobians"]
    assert [o.name for o in spec.outputs] == ["Phi_p", "Phi_q", "Phi_s"]
    assert spec.outputs[2].shape == (18, 12)  # passive: c_r, u_1, u_2, r per leg
    assert model_mobility(model).mobility == 3


def test_quantities_command_lists_both_kinds():
    out = subprocess.run(SYMKIN_CLI + ["quantities"], capture_output=True, text=True, check=True).stdout
    rows = {tuple(line.split()[:2]) for line in out.splitlines()[2:]}
    assert {("fk", "serial"), ("fk", "parallel"), ("ik", "parallel"), ("singularities", "parallel"),
            ("closure_jacobians", "parallel"), ("frames", "serial")} <= rows


# --------------------------------------------------------------------------- generic machinery

def _finite_difference_check(model, generated):
    """closure_jacobians are the derivatives of closure (central differences)."""
    rng = np.random.default_rng(31)
    inputs = {i["name"]: rng.uniform(-1, 1, i["shape"][0])
              for f in generated.manifest["functions"] if f["name"] == "closure" for i in f["inputs"]
              if i["kind"] == "vector"}
    J = generated.closure_jacobians(inputs["q"], inputs["s"], inputs["p"])
    for name, block in (("q", J.Phi_q), ("s", J.Phi_s), ("p", J.Phi_p)):
        for j in range(len(inputs[name])):
            plus = {k: v.copy() for k, v in inputs.items()}
            minus = {k: v.copy() for k, v in inputs.items()}
            plus[name][j] += 1e-6
            minus[name][j] -= 1e-6
            fd = (generated.closure(plus["q"], plus["s"], plus["p"])
                  - generated.closure(minus["q"], minus["s"], minus["p"])) / 2e-6
            np.testing.assert_allclose(block[:, j], fd, atol=1e-7)


@pytest.mark.parametrize("name", ["delta", "stewart"])
def test_closure_jacobians_are_the_derivatives_of_the_closure(name, models, generated_dir):
    _finite_difference_check(models[name], load(generated_dir / name))


def test_delta_loop_closure_agrees_with_the_closed_forms(generated_dir):
    delta = load(generated_dir / "delta")
    rng = np.random.default_rng(32)
    p = np.column_stack([rng.uniform(-0.04, 0.04, (500, 2)), rng.uniform(-0.18, -0.12, 500)])
    theta = delta.ik(p).joints
    report = solve_closure(delta, theta, np.zeros(12), p, unknowns=("s",))
    assert report.all_converged, report.residual.max()
    assert report.residual.max() <= NEWTON * DELTA_SCALE, report.residual.max()
    s = report.solution["s"]
    J = delta.closure_jacobians(theta, s, p)
    A = np.concatenate([J.Phi_p, J.Phi_s], axis=-1)  # 18 x 15, consistent
    X = -np.linalg.pinv(A) @ J.Phi_q
    np.testing.assert_allclose(X[:, :3], delta.jacobian(theta, p), atol=1e-12)
    fk = solve_closure(delta, theta, s + 0.05, p + 0.01, unknowns=("p", "s"))
    assert fk.all_converged
    np.testing.assert_allclose(fk.solution["p"], p, atol=1e-12)
    ik = solve_closure(delta, theta + 0.05, s, p, unknowns=("q", "s"))
    np.testing.assert_allclose(ik.solution["q"], theta, atol=1e-12)


@pytest.mark.parametrize("text, box", [
    (LINEAR_DELTA, ([-0.04, -0.04, -0.15], [0.04, 0.04, -0.05])),
    (TSAI_UPU, ([-0.05, -0.05, -0.25], [0.05, 0.05, -0.15])),
])
def test_new_topologies_need_only_a_model_file(text, box, tmp_path):
    """PUU and UPU (two of the seed's six TPM topologies): IK, trilateration FK and J from the model file."""
    model, generated = _derive(text, tmp_path)
    assert model_mobility(model).mobility == 3
    rng = np.random.default_rng(33)
    p = rng.uniform(*box, (2000, 3))
    ik = generated.ik(p)
    assert np.all(ik.margin > 0)
    fk = generated.fk(ik.joints)
    np.testing.assert_allclose(fk.position, p, atol=1e-12)
    # squared lengths minus squared lengths (terms <= (0.32 m)^2 = 0.1 m^2) that vanish at the IK
    np.testing.assert_allclose(generated.constraints(ik.joints, p), 0, atol=KINEMATICS * 0.1)
    J = generated.jacobian(ik.joints, p)
    h = 1e-6
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        fd = (generated.fk(ik.joints + step).position - generated.fk(ik.joints - step).position) / (2 * h)
        np.testing.assert_allclose(J[:, :, j], fd, atol=1e-7 * np.abs(J).max())
    newton = solve_fk(generated, ik.joints, p + 0.005)
    assert newton.all_converged
    np.testing.assert_allclose(newton.solution, p, atol=1e-12)


def test_manifest_records_the_parallel_structure(generated_dir):
    delta = load(generated_dir / "delta")
    record = delta.manifest["model"]["parallel"]
    assert record["motion"] == "translation"
    assert record["home"] == [0.0, 0.0, -0.15]
    assert [leg["topology"] for leg in record["legs"]] == ["RUU"] * 3
    theta1 = delta.manifest["model"]["coordinates"][0]
    assert theta1["name"] == "theta1"
    assert theta1["type"] == "R"
    assert theta1["limits"] == pytest.approx([-np.pi / 2, np.pi / 3], rel=EPS)  # actuator_limits, rounded once
    ik = next(f for f in delta.manifest["functions"] if f["name"] == "ik")
    assert ik["inputs"][0]["name"] == "p"
    assert ik["inputs"][0]["elements"] == ["x", "y", "z"]
    assert [o["name"] for o in ik["outputs"]] == ["joints", "margin"]


def test_parallel_runtime_does_not_import_sympy(generated_dir):
    code = ("import sys, numpy as np; from symkin import load; from symkin.runtime.parallel import solve_fk; "
            f"m = load({str(generated_dir / 'stewart')!r}); p = np.array([0, 0, 0.23, 0, 0, 0.1]); "
            "r = solve_fk(m, m.ik(p).joints, p + 0.01); print(r.all_converged, 'sympy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["True", "False"]


def test_example_model_files_exist():
    assert (MODELS_DIR / "delta.yaml").exists()
    assert (MODELS_DIR / "stewart.yaml").exists()

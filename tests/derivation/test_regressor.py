"""Issue 33, step 1: the dynamics regressor tau = Y(q, qd, qdd) pi, linear in the standard parameters.

References: Y pi against the inverse dynamics symbolically (the seed's 2R arm with drives and friction) and
numerically (every serial example model, a tree with gyroscopic rotors and couplings); Y and pi against
Pinocchio's computeJointTorqueRegressor and Inertia.toDynamicParameters on the UR10e's URDF; the generated
numpy, C and CasADi code against the generated inverse dynamics.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
import sympy

from conftest import MODELS_DIR, random_q, reference_function
from symkin import pipeline
from symkin.derivation import Derivation
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.dynamics.regressor import parameter_names
from symkin.ir.evaluate import lambdify_spec
from symkin.model import load_model, model_from_text
from symkin.runtime.loader import load
from tolerances import DYNAMICS, EPS
from sample_models import DRIVEN, PARAMETERS, PLANAR

#: The same with gyroscopic rotors: a tree (each rotor joint a branch on the link before its joint) whose rotor
#: joints are coupled to the coordinates (angle N q).
ROTORS = PLANAR.replace(PARAMETERS, PARAMETERS + "  J1: 1.2e-6\n  N1: 13.3\n  J2: 3.4e-6\n  N2: 7\n") + """
actuators:
  theta1: {rotor_inertia: J1, gear_ratio: N1, gyroscopic: true}
  theta2: {rotor_inertia: J2, gear_ratio: N2, gyroscopic: true}
friction:
  theta2: {viscous: 0.05, coulomb: 0.1}
"""
SERIAL_EXAMPLES = ("planar_2r", "ur10e", "ur10e_classic")


def _check_y_pi(model, d, rng, samples=8):
    """Y pi = tau at random states, to DYNAMICS relative to sum_k |Y_k pi_k| (the dot product adds <= 14 n
    roundings of u to the evaluations' DYNAMICS: within the bound's margin for n <= 7)."""
    Y_pi = reference_function(model, d["regressor"])
    tau = reference_function(model, d["inverse_dynamics"])
    for _ in range(samples):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-5, 5, model.dof)
        Y, pi = Y_pi(q, qd, qdd)
        scale = float(np.max(np.abs(Y) @ np.abs(pi)))
        error = float(np.max(np.abs(Y @ pi - tau(q, qd, qdd)[0])))
        assert error <= DYNAMICS * scale, f"{model.name}: error {error:.3g} at q={q}, qd={qd}, qdd={qdd}"


def test_y_pi_is_the_inverse_dynamics_of_the_driven_planar_arm_exactly():
    """Symbolic: Y pi - tau simplifies to zero with the drives' reflected inertia and the friction in pi."""
    model = model_from_text(DRIVEN, "driven")
    d = Derivation(model)
    Y, pi = d["regressor"].expanded_outputs()
    tau = d["inverse_dynamics"].expanded_outputs()[0]
    assert sympy.simplify(Y * pi - tau) == sympy.zeros(2, 1)
    names = parameter_names(model)
    assert names[:10] == tuple(f"link1.{p}" for p in INERTIAL)
    assert names[20:24] == tuple(f"theta1.{p}" for p in DRIVE)
    J1, N1, b1 = (model.parameter(n).symbol for n in ("J1", "N1", "b1"))
    values = dict(zip(names, pi))
    # the conversion from SymEngine leaves products unsorted: compare by difference
    assert sympy.simplify(values["theta1.Ia"] - N1 ** 2 * J1) == 0
    assert sympy.simplify(values["theta1.fv"] - b1) == 0
    assert values["link2.mz"] == 0  # the planar arm's links carry their masses in their x-y plane


@pytest.mark.parametrize("name", SERIAL_EXAMPLES)
def test_y_pi_is_the_inverse_dynamics_of_every_serial_example(name, models, derivations):
    _check_y_pi(models[name], derivations[name], np.random.default_rng(33))


def test_y_pi_through_a_tree_of_coupled_rotor_joints():
    """Gyroscopic rotors are bodies on branch links moved by coupled joints: their ten parameters reach the
    coordinates through A^T as every other term does."""
    model = model_from_text(ROTORS, "rotors")
    assert [j.link for j in model.joints] == ["link1_rotor", "link1", "link2_rotor", "link2"]
    assert parameter_names(model)[:10] == tuple(f"link1_rotor.{p}" for p in INERTIAL)
    _check_y_pi(model, Derivation(model), np.random.default_rng(34))


def _check_energy(model, d, rng, samples=8):
    """Y_e pi = k + u at random states, to DYNAMICS relative to sum_k |Y_e,k pi_k| (a dot product of the
    evaluated columns, as :func:`_check_y_pi`)."""
    Y_pi = reference_function(model, d["energy_regressor"])
    kinetic = reference_function(model, d["kinetic_energy"])
    potential = reference_function(model, d["potential_energy"]) if any(model.gravity) else None
    for _ in range(samples):
        q, qd = random_q(model, rng), rng.uniform(-2, 2, model.dof)
        Y_e, pi = Y_pi(q, qd)
        energy = float(kinetic(q, qd)[0]) + (float(potential(q)[0]) if potential is not None else 0.0)
        scale = float(np.abs(Y_e) @ np.abs(pi))
        assert abs(float(Y_e @ pi) - energy) <= DYNAMICS * scale, f"{model.name}: at q={q}, qd={qd}"


@pytest.mark.parametrize("name", SERIAL_EXAMPLES + ("phantom_premium",))
def test_the_energy_regressor_gives_the_energy_of_every_serial_example(name, models, derivations):
    _check_energy(models[name], derivations[name], np.random.default_rng(35))


def test_the_energy_regressor_through_a_tree_of_coupled_rotor_joints_and_drives():
    """Gyroscopic rotors on branch links, and the reflected rotor inertia of plain drives (1/2 I_a qd^2)."""
    for text, name in ((ROTORS, "rotors"), (DRIVEN, "driven")):
        model = model_from_text(text, name)
        _check_energy(model, Derivation(model), np.random.default_rng(36))


def test_the_energy_changes_at_the_rate_of_the_power_of_the_efforts():
    """d(Y_e pi)/dt = qd . (tau - F_f) along a motion (the identity identification from the power rests on):
    the UR10e moved along q(t) = q0 + a t + b t^2, the derivative by a central difference (step h: truncation
    ~ h^2, rounding ~ eps |h| / h), the power from the generated inverse dynamics."""
    model = load_model(MODELS_DIR / "ur10e.yaml")
    d = Derivation(model)
    Y_pi = reference_function(model, d["energy_regressor"])
    tau = reference_function(model, d["inverse_dynamics"])
    rng = np.random.default_rng(37)
    q0, a, b = random_q(model, rng), rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6)

    def energy(t):
        Y_e, pi = Y_pi(q0 + a * t + b * t * t, a + 2 * b * t)
        return float(Y_e @ pi)
    h = 1e-4
    rate = (energy(h) - energy(-h)) / (2 * h)
    power = float(a @ tau(q0, a, 2 * b)[0])  # the UR10e model has no friction
    assert rate == pytest.approx(power, rel=1e-6, abs=1e-6 * abs(energy(0.0)))


def test_asymmetric_coulomb_friction_is_an_offset_while_the_joint_moves():
    """Levels c+ != c-: pi holds f_c = (c+ + c-)/2 and f_o = (c+ - c-)/2, so Y pi = tau wherever the joint moves
    (sign(qd)^2 = 1) and differs by f_o at rest, where the model's friction vanishes."""
    model = model_from_text(PLANAR + "friction:\n  theta1: {coulomb: {positive: 0.4, negative: 0.25}}\n", "asym")
    d = Derivation(model)
    values = dict(zip(parameter_names(model), reference_function(model, d["regressor"])(
        [0.1, 0.2], [1.0, 1.0], [0.0, 0.0])[1]))
    assert values["theta1.fc"] == pytest.approx(0.325, abs=4 * EPS)
    assert values["theta1.fo"] == pytest.approx(0.075, abs=4 * EPS)
    Y_pi, tau = reference_function(model, d["regressor"]), reference_function(model, d["inverse_dynamics"])
    for qd, offset in (([1.0, -0.5], 0.0), ([-1.0, 0.5], 0.0), ([0.0, 0.5], 0.075)):
        Y, pi = Y_pi([0.1, 0.2], qd, [0.3, -0.2])
        assert (Y @ pi - tau([0.1, 0.2], qd, [0.3, -0.2])[0])[0] == pytest.approx(offset, abs=DYNAMICS)


def test_the_regressor_is_pinocchios_on_the_ur10e_urdf():
    """A URDF's joint frame is its child link's frame, Newton-Euler's F_i: the 60 inertial columns are
    computeJointTorqueRegressor's, pi's first 60 entries the links' toDynamicParameters (same order)."""
    pmodel = pin.buildModelFromUrdf(str(MODELS_DIR / "ur10e.urdf"))
    pdata = pmodel.createData()
    model = load_model(MODELS_DIR / "ur10e.urdf")
    Y_pi = reference_function(model, Derivation(model)["regressor"])
    rng = np.random.default_rng(35)
    pin_pi = np.concatenate([pmodel.inertias[i].toDynamicParameters() for i in range(1, pmodel.njoints)])
    for _ in range(5):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        Y, pi = Y_pi(q, qd, qdd)
        want = pin.computeJointTorqueRegressor(pmodel, pdata, q, qd, qdd)
        scale = float(np.max(np.abs(want)))
        np.testing.assert_allclose(Y[:, :60], want, rtol=0, atol=DYNAMICS * scale)
        assert not np.any(Y[:, 60:] @ pi[60:])  # the URDF declares neither drives nor friction
    np.testing.assert_allclose(pi[:60], pin_pi, rtol=0, atol=4 * EPS * float(np.max(np.abs(pin_pi))))


def test_the_generated_regressor_in_numpy_c_and_casadi(tmp_path):
    """One call gives (Y, pi); the manifest names pi's elements; each backend's Y pi is its inverse dynamics."""
    model = model_from_text(DRIVEN, "driven")
    request = pipeline.resolve_request(model, ("regressor", "base_regressor", "inverse_dynamics"), "numpy,c,casadi",
                                       None, False, "none")
    written = pipeline.write(pipeline.generate(model, request), tmp_path)
    manifest = json.loads((written / "manifest.json").read_text())
    record = next(f for f in manifest["functions"] if f["name"] == "regressor")
    assert [o["elements"] for o in record["outputs"]] == [list(parameter_names(model))] * 2
    rng = np.random.default_rng(36)
    q, qd, qdd = rng.uniform(-2, 2, (3, 20, 2))
    for backend in ("numpy", "c", "casadi"):
        generated = load(written, backend)
        Y, pi = generated.regressor(q, qd, qdd)
        assert Y.shape == (20, 2, 28)
        assert pi.shape == (20, 28)
        tau = generated.inverse_dynamics(q, qd, qdd)
        scale = np.max(np.einsum("bij,bj->bi", np.abs(Y), np.abs(pi)))
        np.testing.assert_allclose(np.einsum("bij,bj->bi", Y, pi), tau, rtol=0, atol=DYNAMICS * scale)
        for l1 in (0.1, 0.25):  # the default and a longer first link: pi_b regroups link 2's mass with l1
            Y_b, pi_b = generated.base_regressor(q, qd, qdd, l1=l1)
            tau = generated.inverse_dynamics(q, qd, qdd, l1=l1)
            scale = np.max(np.einsum("bij,bj->bi", np.abs(Y_b), np.abs(pi_b)))
            np.testing.assert_allclose(np.einsum("bij,bj->bi", Y_b, pi_b), tau, rtol=0, atol=DYNAMICS * scale)


def test_the_planar_arms_base_parameters_are_khalils_regrouping():
    """The 2R arm (l1 = 0.1 m) with drives: link 2's mass acts as a first moment and an inertia of link 1, the first
    rotor as link 1's I_zz (Khalil and Dombre 2002, sec. 12.5: MXR1 = MX1 + l1 M2, ZZR1 = ZZ1 + l1^2 M2 + Ia1);
    what no motion of a planar arm excites (m_z, I_xx...) is gone."""
    d = Derivation(model_from_text(DRIVEN, "driven"))
    found = d["base_parameters"]
    assert found.base_names == ("link1.mxR", "link1.my", "link1.IzzR", "link2.mx", "link2.my", "link2.Izz",
                                "theta1.fv", "theta1.fc", "theta1.fo", "theta2.Ia", "theta2.fv", "theta2.fc",
                                "theta2.fo")
    l1 = sympy.Symbol("l1")
    mx, Izz = (found.base_names.index(n) for n in ("link1.mxR", "link1.IzzR"))
    m2, Ia1 = (found.names.index(n) for n in ("link2.m", "theta1.Ia"))
    assert found.combinations[mx][m2] == l1
    assert found.combinations[Izz][m2] == l1 ** 2
    assert found.combinations[Izz][Ia1] == 1
    assert found.geometry == ("l1",)
    assert found.equations()[mx] == "link1.mxR = link1.mx + l1 link2.m"
    assert found.equations()[Izz] == "link1.IzzR = link1.Izz + l1**2 link2.m + theta1.Ia"
    assert found.evaluate({"l1": 0.25})[Izz, m2] == 0.0625
    with pytest.raises(ValueError, match="K depends on l1: give the value of l1"):
        found.evaluate({"l2": 0.25})


def _off_default(model, rng, names):
    """The model's parameter values with ``names`` moved to random values of 0.5 to 1.5 times their defaults."""
    values = dict(model.parameter_values)
    for name in names:
        symbol = model.parameter(name).symbol
        values[symbol] = sympy.Float(float(values[symbol]) * rng.uniform(0.5, 1.5))
    return values


def test_the_regrouping_holds_at_every_geometry_not_only_the_defaults(models, derivations):
    """The UR10e with its lengths and offsets moved off their defaults: Y = Y_b K(P) at random states, K evaluated
    at the moved values (a K taken at the defaults misses by the moved lengths); K is Khalil's with the geometry
    kept (link 3's mass in link 2's first moment as a2 m3, link 5's in the shoulder's inertia as
    (a2^2 + a3^2 + d4^2) m5)."""
    model, d = models["ur10e"], derivations["ur10e"]
    found = d["base_parameters"]
    a2, a3, d4 = sympy.symbols("a2 a3 d4")
    row = dict(zip(found.base_names, found.combinations))
    assert row["upper_arm.mxR"][found.names.index("forearm.m")] == a2
    assert sympy.expand(row["shoulder.IzzR"][found.names.index("wrist2.m")] - (a2 ** 2 + a3 ** 2 + d4 ** 2)) == 0
    assert set(found.geometry) == {"a2", "a3", "d4", "d5"}
    rng = np.random.default_rng(40)
    spec = d["regressor"]
    for _ in range(3):
        values = _off_default(model, rng, found.geometry)
        Y_pi = lambdify_spec(spec, [list(i.symbols) for i in spec.vector_inputs], "numpy", values)
        K = found.evaluate({name: float(values[model.parameter(name).symbol]) for name in found.geometry})
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        Y = np.array(Y_pi(q, qd, qdd)[:6 * len(found.names)], dtype=float).reshape(6, -1)
        Y_b = Y[:, list(found.base)]
        np.testing.assert_allclose(Y_b @ K, Y, rtol=0, atol=DYNAMICS * float(np.max(np.abs(Y_b) @ np.abs(K))))


def _stacked(function, model, rng, states):
    return [function(random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-5, 5, model.dof))
            for _ in range(states)]


def test_the_base_regressor_has_full_rank_and_the_same_torques(models, derivations):
    """UR10e: Y = Y_b K and Y pi = Y_b pi_b at random states, and the stacked Y_b has full column rank (its
    smallest singular value far above the rounding of its entries)."""
    model, d = models["ur10e"], derivations["ur10e"]
    full, base = reference_function(model, d["regressor"]), reference_function(model, d["base_regressor"])
    K = d["base_parameters"].evaluate({p.name: float(p.value) for p in model.parameters})
    rng = np.random.default_rng(37)
    stacked = []
    for q, qd, qdd in _stacked(lambda *state: state, model, rng, 30):
        (Y, pi), (Y_b, pi_b) = full(q, qd, qdd), base(q, qd, qdd)
        scale = float(np.max(np.abs(Y_b) @ np.abs(K)))
        np.testing.assert_allclose(Y_b @ K, Y, rtol=0, atol=DYNAMICS * scale)
        np.testing.assert_allclose(Y_b @ pi_b, Y @ pi, rtol=0, atol=DYNAMICS * float(np.max(np.abs(Y) @ np.abs(pi))))
        stacked.append(Y_b)
    singular = np.linalg.svd(np.vstack(stacked), compute_uv=False)
    assert singular[-1] > 1e6 * EPS * singular[0] * len(singular)


def test_the_number_of_base_inertial_parameters_is_the_rank_of_pinocchios_regressors():
    """The UR10e's 60 inertial parameters (its URDF, angles snapped to multiples of 90 deg) have as many base
    combinations as Pinocchio's stacked joint-torque regressors have rank over random states (SVD, default
    tolerance: the exact count against an independent numeric one)."""
    from symkin.dynamics.base_parameters import base_parameters

    model = load_model(MODELS_DIR / "ur10e.urdf", snap_angles=True)
    d = Derivation(model)
    inertial = base_parameters(model, [row[:60] for row in d["regressor_graph"]], parameter_names(model)[:60])
    pmodel = pin.buildModelFromUrdf(str(MODELS_DIR / "ur10e.urdf"))
    pdata = pmodel.createData()
    rng = np.random.default_rng(38)
    stacked = np.vstack([pin.computeJointTorqueRegressor(pmodel, pdata, *state).copy()
                         for state in _stacked(lambda *state: state, model, rng, 40)])
    assert len(inertial.base) == np.linalg.matrix_rank(stacked) == 36


def test_the_stock_ur10_gets_its_base_parameters_with_its_angles_snapped():
    """Issue 61: example-robot-data's UR10 writes pi/2 as 1.57079632679 (4.9e-12 off): as written its geometry is not
    rational and the base parameters refuse it with the fix (--snap-angles); snapped as the digits written allow,
    it gets them, as many as the numeric rank of Pinocchio's stacked regressors of the file (36 of 60)."""
    from sample_models import ROBOTS_DIR
    from symkin.dynamics.base_parameters import base_parameters
    from symkin.errors import DerivationError

    path = ROBOTS_DIR / "ur_description/urdf/ur10_robot.urdf"
    with pytest.raises(DerivationError, match="--snap-angles"):
        Derivation(load_model(path, tip="tool0", chain=True))["base_parameters"]
    model = load_model(path, tip="tool0", chain=True, snap_angles=True)
    assert "1.57079632679 as pi/2" in model.notes[-1]
    d = Derivation(model)
    inertial = base_parameters(model, [row[:60] for row in d["regressor_graph"]], parameter_names(model)[:60])
    pmodel = pin.buildModelFromUrdf(str(path))
    pdata = pmodel.createData()
    rng = np.random.default_rng(39)
    stacked = np.vstack([pin.computeJointTorqueRegressor(pmodel, pdata, *state).copy()
                         for state in _stacked(lambda *state: state, model, rng, 40)])
    assert len(inertial.base) == np.linalg.matrix_rank(stacked) == 36


def _tree_urdf(rng) -> str:
    """A branched robot nobody tuned: a turning torso carrying two 2-joint arms, random link offsets (3 decimals,
    exact as written) and random physical inertias, one arm's shoulder axis turned by rpy 1.5708 (snapped)."""
    def inertial(mass: float) -> str:
        a, b = rng.uniform(0.01, 0.05, 2)
        xx, yy, zz = a, b, rng.uniform(abs(a - b) + 0.005, a + b)  # the triangle inequality with room
        com = " ".join(f"{v:.3f}" for v in rng.uniform(-0.1, 0.1, 3))
        return (f'<inertial><origin xyz="{com}"/><mass value="{mass:.3f}"/>'
                f'<inertia ixx="{xx:.4f}" iyy="{yy:.4f}" izz="{zz:.4f}" ixy="0" ixz="0" iyz="0"/></inertial>')

    links = ["base", "torso", "l_upper", "l_fore", "r_upper", "r_fore"]
    joints = [("waist", "base", "torso", "0 0 1", "0 0 0"), ("l_shoulder", "torso", "l_upper", "0 1 0", "0 0 0"),
              ("l_elbow", "l_upper", "l_fore", "0 1 0", "0 0 0"), ("r_shoulder", "torso", "r_upper", "1 0 0",
                                                                   "1.5708 0 0"),
              ("r_elbow", "r_upper", "r_fore", "0 0 1", "0 0 0")]
    text = ['<robot name="two_arms">']
    text += [f'<link name="{name}">{inertial(rng.uniform(0.5, 3)) if name != "base" else ""}</link>' for name in links]
    for name, parent, child, axis, rpy in joints:
        xyz = " ".join(f"{v:.3f}" for v in rng.uniform(-0.3, 0.3, 3))
        text.append(f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
                    f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>'
                    '<limit lower="-3" upper="3" effort="10" velocity="2"/></joint>')
    return "\n".join(text + ["</robot>"])


def test_a_branched_tree_s_base_parameters_are_as_many_as_pinocchios_regressor_rank(tmp_path):
    """Issue 61: the whole tree of a robot file (two arms on a turning torso, read with no tip) gets its base
    parameters, as many as the numeric rank of Pinocchio's stacked joint-torque regressors of the same file (the
    exact count of an algorithm that walks the tree against an independent numeric one)."""
    from symkin.dynamics.base_parameters import base_parameters

    rng = np.random.default_rng(61)
    path = tmp_path / "two_arms.urdf"
    path.write_text(_tree_urdf(rng))
    model = load_model(path, snap_angles=True)
    assert model.dof == 5
    inertial = base_parameters(model, [row[:50] for row in Derivation(model)["regressor_graph"]],
                               parameter_names(model)[:50])
    pmodel = pin.buildModelFromUrdf(str(path))
    pdata = pmodel.createData()
    stacked = np.vstack([pin.computeJointTorqueRegressor(pmodel, pdata, *state).copy()
                         for state in _stacked(lambda *state: state, model, rng, 40)])
    assert len(inertial.base) == np.linalg.matrix_rank(stacked)


def test_what_rational_arithmetic_cannot_evaluate_is_refused_with_the_fix():
    from symkin.errors import DerivationError

    with pytest.raises(DerivationError, match="--snap-angles"):
        Derivation(load_model(MODELS_DIR / "ur10e.urdf"))["base_parameters"]
    with pytest.raises(DerivationError, match="non-integer multiple of a coordinate"):
        Derivation(model_from_text(ROTORS, "rotors"))["base_parameters"]

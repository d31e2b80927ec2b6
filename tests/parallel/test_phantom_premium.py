"""The PHANToM Premium 1.5 (models/phantom_premium.yaml) against Cavusoglu, Feygin and Tendick (2002).

The paper's closed forms of M, C and G, in its coordinates (q1 base yaw, q2 upper arm, q3 the distal
link's absolute angle) and inertia model, as transcribed in the Rice MAHI lab's public PHANToM code
(github.com/mahilab/Phantom, cpp/Phantom.hpp, Phantom::update1).  symkin derives the arm from its
parallelogram (a second branch of bodies and two coupled joints) and its capstan drives; with every
parameter a free symbol:

* M - diag(N_i^2 J_m) equals the paper's M (the paper has no rotor inertia) and G the paper's G;
* symkin's C (Christoffel's symbols of M) equals the printed C in every entry but C32, which the
  print has with the wrong sign: with it dM/dt - 2C is not skew-symmetric.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy
from sympy import Rational, cos, sin

from conftest import GENERATED_DIR
from symkin import load
from symkin.model import coordinates
from tolerances import CLOSED_FORM

PAPER_PARAMETERS = ("l1", "l2", "l3", "l5", "l6", "m_a", "m_c", "m_be", "m_df", "I_axx", "I_ayy", "I_azz",
                    "I_cxx", "I_cyy", "I_czz", "I_bexx", "I_beyy", "I_bezz", "I_dfxx", "I_dfyy", "I_dfzz",
                    "I_baseyy", "g")


@pytest.fixture(scope="module")
def phantom(models, derivations):
    model = models["phantom_premium"]
    return model, derivations["phantom_premium"]


def _paper(model):
    """The paper's M, C (as printed) and G in symkin's symbols."""
    q1, q2, q3 = coordinates.symbols(model, "q")
    qd1, qd2, qd3 = coordinates.symbols(model, "qd")
    p = {name: model.parameter(name).symbol for name in PAPER_PARAMETERS}
    l1, l2, l3, l5, l6, g = (p[n] for n in ("l1", "l2", "l3", "l5", "l6", "g"))
    ma, mc, mbe, mdf = (p[n] for n in ("m_a", "m_c", "m_be", "m_df"))
    I = lambda body, axis: p[f"I_{body}{axis}{axis}"]  # noqa: E731 - the paper's I_{body,axis axis}
    k = Rational(1, 2) * l1 * (l2 * ma + l3 * mc)
    arm = 4 * I("be", "y") - 4 * I("be", "z") + 4 * I("c", "y") - 4 * I("c", "z") + l1 ** 2 * (4 * ma + mc)
    distal = 4 * I("a", "y") - 4 * I("a", "z") + 4 * I("df", "y") - 4 * I("df", "z") - l2 ** 2 * ma - 4 * l3 ** 2 * mc
    M11 = (Rational(1, 8) * (4 * I("a", "y") + 4 * I("a", "z") + 8 * p["I_baseyy"] + 4 * I("be", "y")
                             + 4 * I("be", "z") + 4 * I("c", "y") + 4 * I("c", "z") + 4 * I("df", "y")
                             + 4 * I("df", "z") + 4 * l1 ** 2 * ma + l2 ** 2 * ma + l1 ** 2 * mc + 4 * l3 ** 2 * mc)
           + Rational(1, 8) * arm * cos(2 * q2) + Rational(1, 8) * distal * cos(2 * q3)
           + 2 * k * cos(q2) * sin(q3))
    M = sympy.Matrix([
        [M11, 0, 0],
        [0, Rational(1, 4) * (4 * (I("be", "x") + I("c", "x") + l1 ** 2 * ma) + l1 ** 2 * mc), -k * sin(q2 - q3)],
        [0, -k * sin(q2 - q3), Rational(1, 4) * (4 * I("a", "x") + 4 * I("df", "x") + l2 ** 2 * ma + 4 * l3 ** 2 * mc)],
    ])
    C11 = Rational(1, 8) * (-2 * sin(q2) * (arm * cos(q2) + 4 * k * sin(q3)) * qd2
                            + 2 * cos(q3) * (4 * k * cos(q2) - distal * sin(q3)) * qd3)
    C12 = -Rational(1, 8) * (arm * sin(2 * q2) + 8 * k * sin(q2) * sin(q3)) * qd1
    C13 = -Rational(1, 8) * (-8 * k * cos(q2) * cos(q3) + distal * sin(2 * q3)) * qd1
    C = sympy.Matrix([
        [C11, C12, C13],
        [-C12, 0, k * cos(q2 - q3) * qd3],
        [-C13, k * cos(q2 - q3) * qd2, 0],  # C32 as printed
    ])
    G = sympy.Matrix([0, Rational(1, 2) * g * (2 * l1 * ma + 2 * l5 * mbe + l1 * mc) * cos(q2),
                      Rational(1, 2) * g * (l2 * ma + 2 * l3 * mc - 2 * l6 * mdf) * sin(q3)])
    return M, C, G


def _is_zero(expr) -> bool:
    """Exact: gear ratios such as 13.3 are read as floats, so numbers are made rational first."""
    return sympy.simplify(sympy.expand_trig(sympy.nsimplify(sympy.expand(expr), rational=True))) == 0


def _output(derivation, name):
    return sympy.Matrix(derivation[name].expanded_outputs()[0])


def test_mass_matrix_is_the_papers_plus_the_reflected_rotor_inertia(phantom):
    model, derivation = phantom
    M_paper, _, _ = _paper(model)
    # each motor's N^2 J_m on its coordinate's diagonal: q1, q2 and (through the lever) q3
    drives = {"q1": "q1", "q2": "q2", "lever_joint": "q3"}
    names = [c.name for c in model.coordinates]
    reflected = sympy.zeros(3, 3)
    for actuator in model.actuators:
        k = names.index(drives[actuator.joint])
        reflected[k, k] += actuator.reflected_inertia
    M = _output(derivation, "mass_matrix")
    for i in range(3):
        for j in range(3):
            assert _is_zero(M[i, j] - reflected[i, j] - M_paper[i, j]), (i, j)


def test_gravity_vector_is_the_papers(phantom):
    model, derivation = phantom
    _, _, G_paper = _paper(model)
    G = _output(derivation, "gravity_vector")
    for i in range(3):
        assert sympy.simplify(G[i] - G_paper[i]) == 0, i


def test_coriolis_matrix_is_the_papers_but_for_its_misprinted_C32(phantom):
    model, derivation = phantom
    _, C_paper, _ = _paper(model)
    C = _output(derivation, "coriolis_matrix")
    for i in range(3):
        for j in range(3):
            if (i, j) == (2, 1):
                assert _is_zero(C[i, j] + C_paper[i, j])  # the paper's sign is wrong
            else:
                assert _is_zero(C[i, j] - C_paper[i, j]), (i, j)


def test_the_printed_C32_breaks_the_skew_symmetry_of_dM_dt_minus_2C(phantom):
    """N = dM/dt - 2C: N23 + N32 = 0 with Christoffel's C32, -4 k cos(q2 - q3) qd2 with the printed one."""
    model, _ = phantom
    M, C_printed, _ = _paper(model)
    q = coordinates.symbols(model, "q")
    qd = coordinates.symbols(model, "qd")
    dM = sympy.Matrix(3, 3, lambda i, j: sum(sympy.diff(M[i, j], q[k]) * qd[k] for k in range(3)))
    C_right = C_printed.copy()
    C_right[2, 1] = -C_printed[2, 1]
    printed, right = dM - 2 * C_printed, dM - 2 * C_right
    assert _is_zero(right[1, 2] + right[2, 1])
    assert not _is_zero(printed[1, 2] + printed[2, 1])
    for i, j in ((0, 1), (0, 2), (0, 0), (1, 1), (2, 2)):
        assert _is_zero(right[i, j] + right[j, i]), (i, j)


def test_fk_is_the_arm_with_the_absolute_distal_angle(phantom):
    """p = (cos q1 (l1 cos q2 + l2 sin q3), sin q1 (...), l1 sin q2 - l2 cos q3): the TCP moves with q3 alone
    for the distal link, whatever q2 (the parallelogram)."""
    model, derivation = phantom
    q1, q2, q3 = coordinates.symbols(model, "q")
    l1, l2 = model.parameter("l1").symbol, model.parameter("l2").symbol
    radius = l1 * cos(q2) + l2 * sin(q3)
    expected = (cos(q1) * radius, sin(q1) * radius, l1 * sin(q2) - l2 * cos(q3))
    T = _output(derivation, "fk")
    for k in range(3):
        assert _is_zero(T[k, 3] - expected[k]), k


def test_each_coordinate_has_its_motors_effort_limits(models):
    """The q3 motor turns the lever (a follower of q3, multiplier 1): q3's effort limits are its N K_t I."""
    model = models["phantom_premium"]
    values = model.parameter_values
    limits = {c.name: float(c.effort_limit.xreplace(values)) for c in model.coordinates}
    stall, continuous = 0.0234 * 5.5, 0.0234 * 1.24  # K_t I: the motor's torques
    assert limits == pytest.approx({"q1": 13.3 * stall, "q2": 11.2 * stall, "q3": 11.2 * stall}, rel=1e-12)
    # what the motors hold for long, and the motor turns per turn of each coordinate (an encoder's resolution),
    # in the generated code's manifest
    arm = load(GENERATED_DIR / "phantom_premium")
    held = {c.name: c.continuous_effort_limit for c in arm.info.coordinates}
    assert held == pytest.approx({"q1": 13.3 * continuous, "q2": 11.2 * continuous, "q3": 11.2 * continuous},
                                 rel=1e-12)
    assert [c.gear_ratio for c in arm.info.coordinates] == [13.3, 11.2, 11.2]


def test_the_generated_arm_keeps_its_energy_without_friction_and_torques():
    """A free swing of the generated numpy functions (the paper's parameters, no friction, no motor torque):
    the total energy k + u stays put to the integrator's tolerance."""
    from scipy.integrate import solve_ivp

    arm = load(GENERATED_DIR / "phantom_premium")

    def rates(_, x):
        q, qd = x[:3], x[3:]
        M = arm.mass_matrix(q)
        rhs = -arm.coriolis_vector(q, qd) - arm.gravity_vector(q)
        return np.concatenate([qd, np.linalg.solve(M, rhs)])

    x0 = np.array([0.3, 0.4, 0.9, 1.5, -0.5, 2.0])
    solution = solve_ivp(rates, (0.0, 0.5), x0, method="DOP853", rtol=1e-11, atol=1e-12, dense_output=True)
    energies = [float(arm.kinetic_energy(x[:3], x[3:]) + arm.potential_energy(x[:3])) for x in solution.y.T]
    assert solution.success
    assert max(energies) - min(energies) < 1e-8 * max(abs(e) for e in energies) + 1e-12


def test_symkin_rate_reads_the_encoders_gear_ratios_from_the_model():
    """--encoder 4096 alone: the joint steps are 2 pi / (4096 N) with the capstans of the model (q3's through the
    lever), and --gear still overrides them."""
    import argparse

    from symkin.cli.rate_cmd import _encoders, _joint_steps

    arm = load(GENERATED_DIR / "phantom_premium")
    steps = _joint_steps(arm, _encoders(argparse.Namespace(encoder="4096", gear=None), arm))
    assert steps == pytest.approx([2 * np.pi / (4096 * n) for n in (13.3, 11.2, 11.2)], rel=CLOSED_FORM)
    direct = _joint_steps(arm, _encoders(argparse.Namespace(encoder="4096", gear="1"), arm))
    assert direct == pytest.approx([2 * np.pi / 4096] * 3, rel=CLOSED_FORM)


def test_the_datasheets_figures_along_each_axis_at_home_are_the_vendors_by_hand(tmp_path):
    """Issue 64: at the home pose (q = 0, orthogonal arms) the model file's fk p = (cos q1 (l1 cos q2 + l2 sin q3),
    sin q1 (...), l1 sin q2 - l2 cos q3) moves x with q3 alone (dp/dq3 = (l2, 0, 0)), y with q1 (l1) and z with q2
    (l1); each drive renders tau_i = K_t I_stall N_i (Maxon RE 25: 23.4 mN m/A, 5.5 A; capstans 13.3, 11.2, 11.2).
    So the force along x is tau_3 / l2 = 8.479 N (SensAble quotes 8.5 N "at the nominal position"), and one encoder
    count (4096 per motor turn) steps x by l2 2 pi / (4096 N_3) = 23 um (quoted: about 0.03 mm)."""
    import json

    from symkin.cli import main

    l1, l2, K_t, I_stall, I_continuous = 0.215, 0.170, 0.0234, 5.5, 1.24
    gears = np.array([13.3, 11.2, 11.2])
    moved_by = {"x": (2, l2), "y": (0, l1), "z": (1, l1)}         # the joint that moves each axis at home, its lever
    assert main(["rate", str(GENERATED_DIR / "phantom_premium"), "--encoder", "4096", "-n", "64", "--no-figure",
                 "-o", str(tmp_path / "rate")]) == 0
    home = {name: m["home"] for name, m in json.loads((tmp_path / "rate" / "datasheet.json").read_text())[
        "measures"].items()}
    for axis, (joint, lever) in moved_by.items():
        assert home[f"force_{axis}"] == pytest.approx(K_t * I_stall * gears[joint] / lever, rel=CLOSED_FORM)
        assert home[f"continuous_force_{axis}"] == pytest.approx(K_t * I_continuous * gears[joint] / lever,
                                                                 rel=CLOSED_FORM)
        assert home[f"resolution_{axis}"] == pytest.approx(lever * 2 * np.pi / (4096 * gears[joint]), rel=CLOSED_FORM)
    assert home["force_x"] == pytest.approx(8.5, abs=0.05)      # the vendor's figure, to its printed digits


def test_the_declared_home_is_where_the_datasheet_and_the_simulation_start(models):
    """serial.home (the PHANToM's reset pose q = 0, where the middle of its limits is the stretched, singular arm):
    in the model, the manifest, the datasheet's home pose and the simulation's default start."""
    from symkin.rating import datasheet
    from symkin import mechanism
    from symkin.simulation import Plant
    from symkin.simulation.start import start_pose

    assert models["phantom_premium"].home_configuration == (0, 0, 0)
    arm = load(GENERATED_DIR / "phantom_premium")
    assert arm.info.home_configuration == (0.0, 0.0, 0.0)
    limits = mechanism.joint_limits(arm)
    assert np.array_equal(datasheet.home_configuration(arm, limits), np.zeros(3))
    assert not np.array_equal(limits.mean(axis=1), np.zeros(3))  # the declaration decides, not the limits
    q0, how = start_pose(Plant(arm))
    assert np.array_equal(q0, np.zeros(3))
    assert "home configuration" in how

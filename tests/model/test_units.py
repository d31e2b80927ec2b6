"""Issue 60, point 1: ``unit:`` is not decoration - known units are converted to SI by exact factors, unknown
units and units of the wrong dimension are refused, located.

Reference: the seed's 2R arm (models/planar_2r.yaml, in SI) and its twin written in mm, g and deg: the twin's
parameters are the SI values exactly (rationals; pi/180 for degrees) and its derived mass matrix is the same
expression, so generated code cannot tell them apart.
"""

from __future__ import annotations

import sympy
import pytest

from conftest import MODELS_DIR
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import load_model, model_from_text

SI = (MODELS_DIR / "planar_2r.yaml").read_text()
TWIN = (SI.replace("l1: {value: 0.1, unit: m,", "l1: {value: 100, unit: mm,")
        .replace("l2: {value: 0.1, unit: m,", "l2: {value: 10, unit: cm,")
        .replace("m1: {value: 0.1, unit: kg,", "m1: {value: 100, unit: g,")
        .replace("g: {value: 9.81, unit: m/s^2,", "g: {value: 9810, unit: mm/s^2,"))


def test_a_model_in_mm_g_and_deg_derives_what_its_si_twin_derives():
    assert TWIN.count("unit: mm,") == 1  # the replacements took
    si, twin = model_from_text(SI, "planar_2r"), model_from_text(TWIN, "planar_2r")
    assert [(p.name, p.value, p.unit) for p in twin.parameters] == [(p.name, p.value, p.unit) for p in si.parameters]
    assert twin.parameters[0].value == sympy.Rational(1, 10)                 # exact, not 0.1 rounded
    values = si.parameter_values
    M_si = sympy.Matrix(Derivation(si)["mass_matrix"].expanded_outputs()[0]).xreplace(values)
    M_twin = sympy.Matrix(Derivation(twin)["mass_matrix"].expanded_outputs()[0]).xreplace(twin.parameter_values)
    assert sympy.simplify(M_si - M_twin) == sympy.zeros(2, 2)


def test_degrees_are_pi_over_180_and_a_unit_spelled_with_spaces_is_the_same_unit():
    text = SI.replace("  g: {value: 9.81", "  tilt: {value: 90, unit: deg}\n  I: {value: 5, unit: g cm^2}\n"
                                           "  g: {value: 9.81")
    model = model_from_text(text, "planar_2r")
    values = {p.name: (p.value, p.unit) for p in model.parameters}
    assert values["tilt"] == (sympy.pi / 2, "rad")
    assert values["I"] == (sympy.Rational(5, 10**7), "kg*m^2")


@pytest.mark.parametrize("old, new, line, message, fix", [
    ("l1: {value: 0.1, unit: m,", "l1: {value: 60, unit: metres,", 20, "unknown unit 'metres'", "did you mean 'm'"),
    ("l1: {value: 0.1, unit: m,", "l1: {value: 60, unit: mmm,", 20, "unknown unit 'mmm'", "did you mean 'mm'"),
    ("      - [theta1, R, 0, 0, l1, 0, [0, deg(90)]]", "      - [theta1, R, 0, 0, tilt, 0, [0, deg(90)]]", 32,
     "'tilt' is an angle (unit: rad) but is used here as a length", "fix the unit of 'tilt'"),
    ("  g: {value: 9.81", "  half: {expr: l1/2, unit: mm}\n  g: {value: 9.81", 25,
     "a derived parameter's formula computes in SI units", "write unit: m"),
])
def test_a_wrong_unit_is_one_located_error(tmp_path, old, new, line, message, fix):
    text = SI.replace("  g: {value: 9.81", "  tilt: {value: 30, unit: deg}\n  g: {value: 9.81")
    assert old in text
    path = tmp_path / "arm.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ModelError) as raised:
        load_model(path)
    assert len(raised.value.problems) == 1, str(raised.value)
    problem = raised.value.problems[0]
    assert (problem.line, message in problem.message, fix in problem.fix) == (line, True, True), str(problem)


#: The 2R arm with a drive, friction, limits and bodies written with parameters (issue 60: each use site knows the
#: dimension it takes).
PARAMETERIZED = SI.replace("  g: {value: 9.81", "  tilt: {value: 30, unit: deg}\n  K_t: {value: 23.4, unit: mN m/A}\n"
                                               "  I_r: {value: 13, unit: g cm^2}\n  b: {value: 2, unit: mN m s/rad}\n"
                                               "  g: {value: 9.81") + """actuators:
  theta1: {rotor_inertia: I_r, torque_constant: K_t, peak_current: 2}
friction:
  theta1: {viscous: b, coulomb: 0.01}
"""


@pytest.mark.parametrize("old, new, message", [
    ("rotor_inertia: I_r,", "rotor_inertia: m1,", "'m1' is a mass (unit: kg) but is used here as an inertia"),
    ("torque_constant: K_t,", "torque_constant: b,", "used here as a torque constant"),
    ("viscous: b,", "viscous: K_t,", "used here as an angular damping"),
    ("coulomb: 0.01}", "coulomb: l1}", "'l1' is a length (unit: m) but is used here as a torque"),
    ("[0, deg(90)]]\n      - [theta2", "[0, l1]]\n      - [theta2", "'l1' is a length (unit: m) but is used here as an "
                                                                     "angle"),
    ("  - {link: link1, mass: m1}", "  - {link: link1, mass: m1, com: [tilt, 0, 0]}", "used here as a length"),
    ("  - {link: link1, mass: m1}", "  - {link: link1, mass: m1, inertia: {zz: m1}}", "used here as an inertia"),
    ("gravity: [0, -g, 0]", "gravity: [0, -l1, 0]", "'l1' is a length (unit: m) but is used here as an acceleration"),
])
def test_each_use_site_refuses_a_parameter_of_another_dimension(old, new, message):
    assert old in PARAMETERIZED
    model_from_text(PARAMETERIZED, "planar_2r")                                     # as written: accepted
    with pytest.raises(ModelError) as raised:
        model_from_text(PARAMETERIZED.replace(old, new, 1), "planar_2r")
    assert len(raised.value.problems) == 1, str(raised.value)
    assert message in raised.value.problems[0].message


def test_a_number_may_carry_the_dimension_an_inertia_formula_needs():
    """m * 0.04^2 / 12 is an inertia (the number is a length squared): only a parameter standing alone is judged."""
    text = PARAMETERIZED.replace("  - {link: link1, mass: m1}",
                                 "  - {link: link1, mass: m1, inertia: {yy: m1*0.04^2/12, zz: m1*0.04^2/12}}")
    model = model_from_text(text, "planar_2r")
    assert model.bodies[0].inertia[2, 2] == model.parameter("m1").symbol * sympy.Rational(4, 100) ** 2 / 12

"""The seed's 2-DoF arm (sec. 4.4.1): FK and Jacobian equal the closed forms symbolically."""

from __future__ import annotations

import sympy
from sympy import cos, sin

from symkin.model import coordinates


def _seed_symbols(model):
    th1, th2 = coordinates.symbols(model, "q")
    l1, l2 = model.parameter("l1").symbol, model.parameter("l2").symbol
    return th1, th2, l1, l2


def _is_zero(expr) -> bool:
    return sympy.simplify(sympy.expand_trig(expr)) == 0


def test_fk_position_equals_seed_closed_form(models, derivations):
    model = models["planar_2r"]
    th1, th2, l1, l2 = _seed_symbols(model)
    T = derivations["planar_2r"]["fk"].outputs[0].expr
    x_seed = l1 * cos(th1) + l2 * cos(th1 + th2)
    y_seed = l1 * sin(th1) + l2 * sin(th1 + th2)
    assert _is_zero(T[0, 3] - x_seed)
    assert _is_zero(T[1, 3] - y_seed)
    assert T[2, 3] == 0
    # Orientation: a rotation about z by theta1 + theta2.
    R_seed = sympy.Matrix([[cos(th1 + th2), -sin(th1 + th2), 0], [sin(th1 + th2), cos(th1 + th2), 0], [0, 0, 1]])
    assert all(_is_zero(e) for e in (T[:3, :3] - R_seed))


def test_jacobian_equals_seed_eq_8_56(models, derivations):
    model = models["planar_2r"]
    th1, th2, l1, l2 = _seed_symbols(model)
    J = derivations["planar_2r"]["jacobian"].outputs[0].expr
    J_seed = sympy.Matrix([
        [-l1 * sin(th1) - l2 * sin(th1 + th2), -l2 * sin(th1 + th2)],
        [l1 * cos(th1) + l2 * cos(th1 + th2), l2 * cos(th1 + th2)],
    ])
    assert J.shape == (2, 2)
    assert all(_is_zero(e) for e in (J - J_seed))


def test_jacobian_is_the_derivative_of_the_task_coordinates(models, derivations):
    """J = dp/dq (seed sec. 4 definition), computed here by plain differentiation."""
    model = models["planar_2r"]
    q = coordinates.symbols(model, "q")
    p = derivations["planar_2r"]["task_coordinates"].outputs[0].expr
    J = derivations["planar_2r"]["jacobian"].outputs[0].expr
    assert all(_is_zero(e) for e in (p.jacobian(q) - J))


def test_determinant_vanishes_exactly_at_stretched_and_folded_arm(models, derivations):
    """det J = l1 l2 sin(theta2): boundary singularities at theta2 = 0 and pi (seed sec. 4.2)."""
    model = models["planar_2r"]
    th1, th2, l1, l2 = _seed_symbols(model)
    J = derivations["planar_2r"]["jacobian"].outputs[0].expr
    assert _is_zero(J.det() - l1 * l2 * sin(th2))

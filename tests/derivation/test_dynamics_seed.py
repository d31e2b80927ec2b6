"""The seed's 2-DoF arm (sec. 4.4.1): M, V, G (eqs. 8.53-8.54) and J^-T M, J^-T V, J^-T G
(eqs. 8.55-8.58) equal the closed forms symbolically (the difference simplifies to zero).

The seed prints eq. 8.45 with a misplaced parenthesis (see models/planar_2r.yaml), but its
matrix form and the M', V', G' below are right.  In particular G'_1 = m1 l1 l2 g cos(th1)
cos(th1 + th2) is correct as printed: in l2 c12 G_1 - (l1 c1 + l2 c12) G_2 the m2 terms
cancel (m2 l2^2 g c12^2 and m2 l1 l2 g c1 c12 appear with both signs), leaving only m1.
"""

from __future__ import annotations

import pytest
import sympy
from sympy import cos, sin

from symkin.model import coordinates


@pytest.fixture(scope="module")
def arm(models, derivations):
    model = models["planar_2r"]
    th1, th2 = coordinates.symbols(model, "q")
    th1d, th2d = coordinates.symbols(model, "qd")
    th1dd, th2dd = coordinates.symbols(model, "qdd")
    p = {name: model.parameter(name).symbol for name in ("l1", "l2", "m1", "m2", "g")}
    return model, derivations["planar_2r"], (th1, th2, th1d, th2d, th1dd, th2dd), p


def _zero(expr) -> bool:
    return sympy.simplify(sympy.expand_trig(sympy.expand(expr))) == 0


def _output(d, name) -> sympy.Matrix:
    return sympy.Matrix(d[name].expanded_outputs()[0])


def test_mass_coriolis_and_gravity_equal_the_seed_matrix_form(arm):
    """Eq. 8.53/8.54: tau = M qdd + V + G."""
    _, d, (th1, th2, th1d, th2d, _, _), p = arm
    l1, l2, m1, m2, g = p["l1"], p["l2"], p["m1"], p["m2"], p["g"]
    M_seed = sympy.Matrix([
        [(m1 + m2) * l1**2 + m2 * l2**2 + 2 * m2 * l1 * l2 * cos(th2), m2 * l2**2 + m2 * l1 * l2 * cos(th2)],
        [m2 * l2**2 + m2 * l1 * l2 * cos(th2), m2 * l2**2]])
    V_seed = sympy.Matrix([-m2 * l1 * l2 * sin(th2) * th2d**2 - 2 * m2 * l1 * l2 * sin(th2) * th1d * th2d,
                           m2 * l1 * l2 * sin(th2) * th1d**2])
    G_seed = sympy.Matrix([m2 * l2 * g * cos(th1 + th2) + (m1 + m2) * l1 * g * cos(th1),
                           m2 * l2 * g * cos(th1 + th2)])
    for got, want in ((_output(d, "mass_matrix"), M_seed), (_output(d, "coriolis_vector"), V_seed),
                      (_output(d, "gravity_vector"), G_seed)):
        assert got.shape == want.shape
        assert all(_zero(e) for e in got - want)


def test_torques_equal_the_seed_equations_of_motion(arm):
    """tau_1 and tau_2 as printed in sec. 4.4.1 (before the matrix form)."""
    _, d, (th1, th2, th1d, th2d, th1dd, th2dd), p = arm
    l1, l2, m1, m2, g = p["l1"], p["l2"], p["m1"], p["m2"], p["g"]
    tau1 = ((m1 + m2) * l1**2 * th1dd + m2 * l2**2 * (th1dd + th2dd) + m2 * l1 * l2 * cos(th2) * (2 * th1dd + th2dd)
            - m2 * l1 * l2 * sin(th2) * th2d**2 - 2 * m2 * l1 * l2 * sin(th2) * th1d * th2d
            + m2 * l2 * g * cos(th1 + th2) + (m1 + m2) * l1 * g * cos(th1))
    tau2 = m2 * l2 * ((th1dd + th2dd) * l2 + l1 * cos(th2) * th1dd + l1 * sin(th2) * th1d**2 + g * cos(th1 + th2))
    tau = _output(d, "inverse_dynamics")
    assert _zero(tau[0] - tau1)
    assert _zero(tau[1] - tau2)


def test_tcp_force_terms_equal_the_seed_M_V_G_primes(arm):
    """F = J^-T (M qdd + V + G) = 1/(l1 l2 sin th2) [M' qdd + V' + G'] (eqs. 8.55-8.60)."""
    _, d, (th1, th2, th1d, th2d, th1dd, th2dd), p = arm
    l1, l2, m1, m2, g = p["l1"], p["l2"], p["m1"], p["m2"], p["g"]
    c1, s1, c2, s2, c12, s12 = cos(th1), sin(th1), cos(th2), sin(th2), cos(th1 + th2), sin(th1 + th2)
    M_prime = sympy.Matrix([
        [(m1 + m2) * l1**2 * l2 * c12 + m2 * l1 * l2**2 * c2 * c12 - m2 * l1 * l2**2 * c1 - m2 * l1**2 * l2 * c1 * c2,
         m2 * l1 * l2**2 * (c2 * c12 - c1)],
        [(m1 + m2) * l1**2 * l2 * s12 + m2 * l1 * l2**2 * c2 * s12 - m2 * l1 * l2**2 * s1 - m2 * l1**2 * l2 * s1 * c2,
         m2 * l1 * l2**2 * (c2 * s12 - s1)]])
    V_prime = sympy.Matrix([
        -m2 * l1 * l2**2 * s2 * c12 * (th1d + th2d)**2 - m2 * l1**2 * l2 * c1 * s2 * th1d**2,
        -m2 * l1 * l2**2 * s2 * s12 * (th1d + th2d)**2 - m2 * l1**2 * l2 * s1 * s2 * th1d**2])
    G_prime = sympy.Matrix([
        m1 * l1 * l2 * g * c1 * c12,
        (m1 + m2) * l1 * l2 * g * c1 * s12 - m2 * l1 * l2 * g * s1 * c12])
    F = _output(d, "tcp_force")
    det = l1 * l2 * s2
    qdd = sympy.Matrix([th1dd, th2dd])
    JTM = F.jacobian(qdd)
    JTV = F.subs({th1dd: 0, th2dd: 0, g: 0})
    JTG = F.subs({th1dd: 0, th2dd: 0, th1d: 0, th2d: 0})
    assert all(_zero(e) for e in det * JTM - M_prime)
    assert all(_zero(e) for e in det * JTV - V_prime)
    assert all(_zero(e) for e in det * JTG - G_prime)


def test_kinetic_energy_is_the_corrected_seed_total(arm):
    """k = 1/2 m1 l1^2 th1d^2 + 1/2 m2 [l1^2 th1d^2 + (th1d + th2d)^2 l2^2 + 2 th1d l1 l2 (th1d + th2d) cos th2]."""
    _, d, (th1, th2, th1d, th2d, _, _), p = arm
    l1, l2, m1, m2, g = p["l1"], p["l2"], p["m1"], p["m2"], p["g"]
    k_seed = (m1 * (l1 * th1d)**2 / 2 + m2 * (l1**2 * th1d**2 + (th1d + th2d)**2 * l2**2
                                                + 2 * th1d * l1 * l2 * (th1d + th2d) * cos(th2)) / 2)
    u_seed = m1 * g * l1 * sin(th1) + m2 * g * (l1 * sin(th1) + l2 * sin(th1 + th2))
    assert _zero(_output(d, "kinetic_energy")[0] - k_seed)
    assert _zero(_output(d, "potential_energy")[0] - u_seed)

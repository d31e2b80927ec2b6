"""UR10e: classic and modified DH agree; the geometric Jacobian is the derivative of FK."""

from __future__ import annotations

import mpmath
import numpy as np
import sympy

from conftest import random_q, reference_function
from symkin.model import coordinates
from tolerances import KINEMATICS, MPMATH_FINITE_DIFFERENCE, UR10E_SCALE


def test_classic_and_modified_dh_give_the_same_tcp_pose(models, derivations):
    rng = np.random.default_rng(1)
    fk_mod = reference_function(models["ur10e"], derivations["ur10e"]["fk"])
    fk_cls = reference_function(models["ur10e_classic"], derivations["ur10e_classic"]["fk"])
    for _ in range(200):
        q = random_q(models["ur10e"], rng)
        np.testing.assert_allclose(fk_mod(q)[0], fk_cls(q)[0], rtol=0, atol=1e-12)


def test_home_pose_matches_the_published_geometry(models, derivations):
    """At q = 0 the flange sits at (a2 + a3, -(d4 + d6), d1 - d5) (UR's DH table)."""
    T = reference_function(models["ur10e"], derivations["ur10e"]["fk"])(np.zeros(6))[0]
    np.testing.assert_allclose(T[:3, 3], [-0.6127 - 0.57155, -(0.17415 + 0.11655), 0.1807 - 0.11985], rtol=0,
                               atol=KINEMATICS * UR10E_SCALE)
    np.testing.assert_allclose(T[:3, :3], [[1, 0, 0], [0, 0, -1], [0, 1, 0]], rtol=0, atol=KINEMATICS)


def _vee(skew: sympy.Matrix) -> list:
    return [skew[2, 1], skew[0, 2], skew[1, 0]]


def test_geometric_jacobian_matches_high_precision_finite_differences_of_fk(models, derivations):
    """Linear rows = dp/dq; angular rows = vee(dR/dq R^T); central differences at 40 digits."""
    for name in ("ur10e", "ur10e_classic", "planar_2r"):
        model = models[name]
        q = coordinates.symbols(model, "q")
        values = model.parameter_values
        T = sympy.Matrix(derivations[name]["fk"].outputs[0].expr).xreplace(values)
        J = sympy.Matrix(derivations[name]["jacobian_geometric"].outputs[0].expr).xreplace(values)
        fk = sympy.lambdify([q], T, modules="mpmath")
        jac = sympy.lambdify([q], J, modules="mpmath")
        rng = np.random.default_rng(2)
        with mpmath.workdps(40):
            h = mpmath.mpf("1e-15")
            for _ in range(5):
                q0 = [mpmath.mpf(float(v)) for v in random_q(model, rng)]
                J0 = jac(q0)
                R = fk(q0)[:3, :3]
                for i in range(model.dof):
                    plus = list(q0)
                    minus = list(q0)
                    plus[i] += h
                    minus[i] -= h
                    dT = (fk(plus) - fk(minus)) / (2 * h)
                    dp = [dT[k, 3] for k in range(3)]
                    w = _vee(sympy.Matrix(dT[:3, :3] * R.T).applyfunc(lambda e: e))
                    for k in range(3):
                        assert abs(J0[k, i] - dp[k]) < MPMATH_FINITE_DIFFERENCE, (name, i, k)
                        assert abs(J0[3 + k, i] - w[k]) < MPMATH_FINITE_DIFFERENCE, (name, i, k)

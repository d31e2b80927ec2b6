"""Closed-form inverse and forward kinematics of legs in distance form (seed sec. 3.2.1).

Inverse kinematics, per leg (seed "Inverse Kinematics" step 3), for the equation
f_i(q_i, p) = (|B_i - C_i|^2 - L_i^2) / 2 = 0 of :mod:`symkin.parallel.distance`, with
v = q_i + offset:

* revolute actuator before the rod (DELTA): C_i runs on a circle, so
  f = alpha + beta cos v + gamma sin v exactly, and

      v = atan2(gamma, beta) + sigma * atan2(sqrt(beta^2 + gamma^2 - alpha^2), -alpha),

  evaluated as one atan2 of the sum's sine and cosine (both scaled by beta^2 + gamma^2 > 0),

      v = atan2(sigma beta sqrt(m) - alpha gamma, -alpha beta - sigma gamma sqrt(m)),   m = beta^2 + gamma^2 - alpha^2,

  so that v lies in (-pi, pi] (the sum of two atan2 spans (-2 pi, 2 pi]: a pantograph's
  elbow-out arm at 132 deg would come out as -228 deg, outside its joint limits).

  This replaces the seed's eqs. (8.18)-(8.20), which are inconsistent (eq. 8.20 has
  theta_1 on both sides, and 8.19 leaves the sign of theta_2 open).  The atan2 form is
  well conditioned everywhere, including near the workspace boundary where arccos is not,
  and the branch is explicit: sigma = +1 puts B_i at a positive rotation (right hand about
  the actuator axis, less than half a turn) from the elbow C_i, sigma = -1 at a negative one.
* prismatic actuator (before the rod, as a linear DELTA, or inside it, as a Stewart-Gough
  strut): f is a quadratic c2 v^2 + c1 v + c0 and sigma = +1 takes the larger root.

In both cases the radicand is returned as the leg's *margin*: >= 0 exactly when the leg
reaches p; where it is negative, the square root makes q_i NaN (IEEE), never a wrong number.

Forward kinematics of a translational platform on three distance legs: trilateration of
the spheres |P - S_i| = L_i, S_i = C_i(q) - b_i (the seed's virtual frames C'_i).  With
u = S2 - S1, v = S3 - S1, n = u x v, subtracting the sphere equations gives
u.(P - S1) = h2 = (L1^2 - L2^2 + |u|^2)/2 and v.(P - S1) = h3 = (L1^2 - L3^2 + |v|^2)/2,
whose solutions are P = S1 + w + t n with

    w = (h2 (v x n) + h3 (n x u)) / |n|^2,    t = sigma sqrt((L1^2 - |w|^2) / |n|^2).

The two roots are mirror images through the plane of the centres; sigma picks the
geometrically meaningful one (for the DELTA: the TCP below its elbows), and the margin
L1^2 - |w|^2 < 0 (no intersection) makes P NaN.

Forward kinematics of a planar point (p = (x, y), the plane z = 0) on two distance legs, as
the pantograph's handle: the same construction in the plane.  The spheres meet z = 0 in the
circles of radius^2 r_i^2 = L_i^2 - S_iz^2 about (S_ix, S_iy); with u = S2 - S1 in the plane
and n = z x u = (-u_y, u_x) its normal in the plane,

    P = S1 + w + t n,    w = (r1^2 - r2^2 + |u|^2) u / (2 |u|^2),    t = sigma sqrt((r1^2 - |w|^2) / |u|^2),

the two assembly modes mirrored through the line of the centres: sigma = +1 puts P to the left
of S1 -> S2 (a positive turn about z), sigma = -1 to the right.

Forward kinematics of an orthogonal spherical platform (the Agile Eye: three R-R-R legs whose middle axes
C_i(q_i) stay at 90 deg from platform axes R b_i, with b_1, b_2, b_3 mutually orthogonal; Bonev, Chablat
and Wenger 2006 show its direct kinematics in closed form).  The columns f_i = R b_i of F = R B are an
orthonormal frame with f_i . C_i = 0.  With u = C_1' / |C_1'| and v = C_1 x u (both perpendicular to C_1),
f_1 = +-(cos phi u + sin phi v); f_3 is perpendicular to f_1 and C_3, so f_3 = +-(C_3 x f_1) / |C_3 x f_1|
(not C_2 x f_1: at the Agile Eye's home pose f_1 = C_2), and f_2 ~ f_1 x (C_3 x f_1) = C_3 - (C_3 . f_1) f_1,
whose condition f_2 . C_2 = 0 reads (C_2 . f_1)(C_3 . f_1) = C_2 . C_3: with a = C_2 . u, b = C_2 . v,
c = C_3 . u, d = C_3 . v, k = C_2 . C_3,

    X cos 2 phi + Y sin 2 phi = Z,   X = ac - bd,  Y = ad + bc,  Z = 2k - ac - bd,

so cos(2 phi - psi) = Z / rho (rho^2 = X^2 + Y^2, psi = atan2(Y, X)) and, with the margin m = rho^2 - Z^2
(>= 0 iff the legs assemble) and the root sigma = +-1,

    rho^2 cos 2 phi = X Z - sigma Y sqrt(m),   rho^2 sin 2 phi = Y Z + sigma X sqrt(m).

Each root leaves the signs of two columns of F free (four solutions).  The legs' ik fixes them: leg i's
branch is the side of f_i . C_i' (C_i' = dC_i/dq_i = u_i x C_i), so f_1 and f_3 take the side s_i of the
home pose (then f_2 = det(B) f_3 x f_1 has its own where the legs are in the home pose's working mode).
The line of f_1 comes from the half angle without a division by cos phi or sin phi:
(1 + cos 2 phi) u + sin 2 phi v = 2 cos phi f and sin 2 phi u + (1 - cos 2 phi) v = 2 sin phi f, each
turned to the side of C_1' and summed, have length 2 (|cos phi| + |sin phi|) >= 2.  R = F B^T; the root is
the home pose's, and p = (roll, pitch, yaw) of R = Rz(yaw) Ry(pitch) Rx(roll).
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import sympy

from symkin.errors import DerivationError
from symkin.parallel.distance import DistanceLeg


@dataclass(frozen=True)
class ClosedForm:
    """A closed-form solution and its margin (>= 0 iff it is real)."""

    value: sympy.Expr
    margin: sympy.Expr


def trig_coefficients(f: sympy.Expr, v: sympy.Symbol) -> tuple[sympy.Expr, sympy.Expr, sympy.Expr]:
    """(alpha, beta, gamma) with f(v) = alpha + beta cos v + gamma sin v.

    Read off exactly from f at v = 0, pi/2, pi, -pi/2, then checked at a random point, so
    that a leg whose equation is not of this form is refused instead of solved wrongly.

    Raises:
        DerivationError: f is not a first-order trigonometric polynomial in v.
    """
    at = {k: f.xreplace({v: angle}) for k, angle in (("0", 0), ("pi", sympy.pi), ("+", sympy.pi / 2),
                                                      ("-", -sympy.pi / 2))}
    alpha = sympy.expand((at["0"] + at["pi"]) / 2)
    beta = sympy.expand((at["0"] - at["pi"]) / 2)
    gamma = sympy.expand((at["+"] - at["-"]) / 2)
    rng = random.Random(7)
    point = {s: sympy.Float(rng.uniform(0.3, 1.3)) for s in f.free_symbols - {v}}
    probe = sympy.Float(rng.uniform(-3, 3))
    expected = f.xreplace(point).xreplace({v: probe})
    model = (alpha + beta * sympy.cos(v) + gamma * sympy.sin(v)).xreplace(point).xreplace({v: probe})
    if abs(sympy.N(expected - model)) > 1e-9 * (1 + abs(sympy.N(expected))):
        raise DerivationError("the leg equation is not of the form alpha + beta cos q + gamma sin q")
    return alpha, beta, gamma


def solve_leg(leg: DistanceLeg) -> ClosedForm:
    """q_i(p) of one leg in distance form, with the branch ``leg.leg.ik_branch``.

    Raises:
        DerivationError: the actuator does not change the leg's equation, or the equation
            has no closed form here.
    """
    f = leg.constraint
    if leg.q not in f.free_symbols:
        raise DerivationError(f"leg '{leg.leg.name}': its actuator {leg.q} does not change the rod's distance")
    v = sympy.Dummy("v", real=True)
    f_v = f.xreplace({leg.q: v - leg.offset})
    sigma = leg.leg.ik_branch
    if leg.rotation:
        alpha, beta, gamma = trig_coefficients(f_v, v)
        margin = beta**2 + gamma**2 - alpha**2
        root = sympy.sqrt(margin)
        value = sympy.atan2(sigma * beta * root - alpha * gamma, -alpha * beta - sigma * gamma * root)
    else:
        poly = sympy.Poly(sympy.expand(f_v), v)
        if poly.degree() != 2 or not poly.LC().is_number:
            raise DerivationError(f"leg '{leg.leg.name}': the rod equation is not a quadratic in {leg.q}")
        c2, c1, c0 = (poly.coeff_monomial(v**k) for k in (2, 1, 0))
        margin = c1**2 - 4 * c2 * c0
        value = (-c1 + sigma * sympy.sign(c2) * sympy.sqrt(margin)) / (2 * c2)
    return ClosedForm(value - leg.offset, margin)


def trilaterate(legs: tuple[DistanceLeg, ...], sigma: int) -> tuple[sympy.Matrix, sympy.Expr]:
    """P(q) of a translational platform on three distance legs and its margin (see module docstring)."""
    S = [sympy.Matrix(leg.C) - sympy.Matrix(leg.b) for leg in legs]
    r2 = [leg.L2 for leg in legs]
    u, v = S[1] - S[0], S[2] - S[0]
    n = u.cross(v)
    nn = n.dot(n)
    h2 = (r2[0] - r2[1] + u.dot(u)) / 2
    h3 = (r2[0] - r2[2] + v.dot(v)) / 2
    w = (h2 * v.cross(n) + h3 * n.cross(u)) / nn
    margin = r2[0] - w.dot(w)
    t = sigma * sympy.sqrt(margin / nn)
    return S[0] + w + t * n, margin


def intersect_circles(legs: tuple[DistanceLeg, ...], sigma: int) -> tuple[sympy.Matrix, sympy.Expr]:
    """(x, y) of a planar point on two distance legs and its margin (see the module docstring)."""
    S = [sympy.Matrix(leg.C) - sympy.Matrix(leg.b) for leg in legs]
    r2 = [leg.L2 - centre[2] ** 2 for leg, centre in zip(legs, S)]
    u = sympy.Matrix([S[1][0] - S[0][0], S[1][1] - S[0][1]])
    n = sympy.Matrix([-u[1], u[0]])
    uu = u.dot(u)
    w = (r2[0] - r2[1] + uu) * u / (2 * uu)
    margin = r2[0] - w.dot(w)
    t = sigma * sympy.sqrt(margin / uu)
    return sympy.Matrix(S[0][:2]) + w + t * n, margin


def require_orthogonal(legs: tuple[DistanceLeg, ...]) -> sympy.Expr:
    """|C_1'| of an orthogonal spherical platform's first leg, after checking that the legs are one (see the module
    docstring).

    Raises:
        DerivationError: a leg's axes are not at 90 deg, the platform axes are not orthogonal, or the first
            leg's middle axis does not turn at a constant rate about the centre.
    """
    if len(legs) != 3 or any(sympy.simplify(leg.L2 - 2) != 0 for leg in legs):
        raise DerivationError("the closed-form fk of a spherical platform needs three legs whose middle and "
                              "platform axes stay at 90 deg (the Agile Eye)")
    b = [sympy.Matrix(leg.b) for leg in legs]
    if any(sympy.simplify(b[i].dot(b[j])) != 0 for i, j in ((0, 1), (0, 2), (1, 2))):
        raise DerivationError("the closed-form fk of a spherical platform needs mutually orthogonal platform "
                              "axes (the Agile Eye)")
    rate = sympy.diff(sympy.Matrix(legs[0].C), legs[0].q)
    speed = sympy.sqrt(sympy.simplify(rate.dot(rate)))
    if speed.free_symbols & {legs[0].q} or speed == 0:
        raise DerivationError(f"leg '{legs[0].leg.name}': its middle axis does not turn at a constant rate")
    return speed


def orthogonal_spherical(legs: tuple[DistanceLeg, ...], signs: tuple[int, int, int]
                         ) -> tuple[sympy.Matrix, sympy.Expr]:
    """R(q) of an orthogonal spherical platform on three legs and its margin, for the signs (sigma, s_1, s_3): the
    root and the sides of f_1 . C_1' and f_3 . C_3' (see the module docstring).

    Raises:
        DerivationError: the legs are not those of an orthogonal spherical platform (:func:`require_orthogonal`).
    """
    speed = require_orthogonal(legs)
    C = [sympy.Matrix(leg.C) for leg in legs]
    rates = [sympy.diff(axis, leg.q) for axis, leg in zip(C, legs)]
    return orthogonal_frame(C, rates, speed, [sympy.Matrix(leg.b) for leg in legs], signs)


def orthogonal_frame(C: list[sympy.Matrix], rates: list[sympy.Matrix], speed: sympy.Expr, b: list[sympy.Matrix],
                     signs: tuple[int, int, int]) -> tuple[sympy.Matrix, sympy.Expr]:
    """R and the margin of :func:`orthogonal_spherical` from the middle axes C_i, their rates C_i', |C_1'| and the
    platform axes b_i (symbols or numbers: the fk's branch is chosen by evaluating it at the home pose)."""
    sigma, side_1, side_3 = signs
    u = rates[0] / speed
    v = C[0].cross(u)
    a, b_, c, d = C[1].dot(u), C[1].dot(v), C[2].dot(u), C[2].dot(v)
    X, Y, Z = a * c - b_ * d, a * d + b_ * c, 2 * C[1].dot(C[2]) - a * c - b_ * d
    rho2 = X**2 + Y**2
    margin = rho2 - Z**2
    root = sympy.sqrt(margin)
    cos2, sin2 = X * Z - sigma * Y * root, Y * Z + sigma * X * root  # rho^2 (cos 2 phi, sin 2 phi)
    halves = [(rho2 + cos2) * u + sin2 * v, sin2 * u + (rho2 - cos2) * v]
    line = sum((h * sympy.sign(h.dot(rates[0])) for h in halves), sympy.zeros(3, 1))
    f1 = side_1 * line / sympy.sqrt(line.dot(line))
    normal = C[2].cross(f1)
    f3 = side_3 * sympy.sign(normal.dot(rates[2])) * normal / sympy.sqrt(normal.dot(normal))
    B = sympy.Matrix.hstack(*b)
    f2 = B.det() * f3.cross(f1)
    return sympy.Matrix.hstack(f1, f2, f3) * B.T, margin


def rpy_of(R: sympy.Matrix) -> sympy.Matrix:
    """(roll, pitch, yaw) of R = Rz(yaw) Ry(pitch) Rx(roll), pitch in [-pi/2, pi/2]."""
    return sympy.Matrix([sympy.atan2(R[2, 1], R[2, 2]),
                         sympy.atan2(-R[2, 0], sympy.sqrt(R[0, 0]**2 + R[1, 0]**2)),
                         sympy.atan2(R[1, 0], R[0, 0])])

"""Generic loop closure of a parallel mechanism declared by legs (seed sec. 3.2, IK steps 1-2).

Step 1, the closed vector chain of leg i: walking its joints from the base must reach the
platform's attachment frame,

    base_T_leg_i * prod_j (origin_j * motion_j(q, s)) = base_T_platform(p) * platform_T_B_i.

Step 2 splits it into Cartesian components: three position rows and three orientation
rows per leg,

    phi_pos = p_end - t,                               t = P + R(p) b_i,
    phi_rot = 2 vee(E - E^T) / (1 + trace E),         E = T^T R_end,  T = R(p) R_Bi,

where vee picks (E32, E13, E21); phi_rot = 2 tan(angle/2) * axis (the Rodrigues vector,
scaled) of the residual rotation E: zero only when the orientations agree, and equal to
the angle vector to first order.  (The simpler vee(E - E^T)/2 = sin(angle) * axis also
vanishes at half turns, where Newton's method converges to assemblies that do not close.)

Step 3 (solving for the unknowns) is closed-form where the leg allows it
(:mod:`symkin.parallel.distance`) and numerical otherwise
(:func:`symkin.runtime.parallel.solve_closure`), with the implicit Jacobians

    Phi_p pdot + Phi_q qdot + Phi_s sdot = 0.

They are formed geometrically, not by differentiating the residual symbolically: a joint
rotating about the base-frame axis w through o moves the leg's end by dp_end = w x (p_end - o)
and dR_end = [w]x R_end, a prismatic joint along a by dp_end = a; the platform coordinates
move t and T.  With dE the matching change of E, the orientation rows change by

    dphi_rot = 2 vee(dE - dE^T) / (1 + tr E) - 2 vee(E - E^T) tr(dE) / (1 + tr E)^2.
"""

from __future__ import annotations

import sympy

from symkin.geometry import skew
from symkin.kinematics.chain import Frame
from symkin.model import joint_kinds
from symkin.parallel.legs import LegChain


def _vee_skew(M: sympy.Matrix) -> sympy.Matrix:
    """vee(M - M^T) = (M32 - M23, M13 - M31, M21 - M12)."""
    return sympy.Matrix([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])



class LegClosure:
    """The closure equations of one leg and their derivatives."""

    def __init__(self, platform: Frame, chain: LegChain):
        self.chain = chain
        self.T = sympy.Matrix(platform.R) * sympy.Matrix(chain.attachment.R)
        self.t = sympy.Matrix(platform.p) + sympy.Matrix(platform.R) * sympy.Matrix(chain.attachment.p)
        self.R_end = sympy.Matrix(chain.end.R)
        self.p_end = sympy.Matrix(chain.end.p)
        self.E = self.T.T * self.R_end
        self.denominator = 1 + self.E.trace()

    def residual(self) -> list[sympy.Expr]:
        """The six closure equations (position rows, then orientation rows)."""
        rotation = 2 * _vee_skew(self.E) / self.denominator
        return list(self.p_end - self.t) + list(rotation)

    def _rows(self, d_position: sympy.Matrix, d_E: sympy.Matrix) -> list[sympy.Expr]:
        d_rotation = (2 * _vee_skew(d_E) / self.denominator
                      - 2 * _vee_skew(self.E) * d_E.trace() / self.denominator**2)
        return list(d_position) + list(d_rotation)

    def joint_derivatives(self) -> dict[sympy.Symbol, list[sympy.Expr]]:
        """d residual / d joint variable, for every joint variable of the leg."""
        out = {}
        for motion in self.chain.motions:
            d_position, w = joint_kinds.twist_column(motion.rotation, motion.direction, motion.point, self.p_end)
            d_E = self.T.T * skew(sympy.Matrix(w)) * self.R_end
            out[motion.variable] = self._rows(sympy.Matrix(d_position), d_E)
        return out

    def task_derivatives(self, task: tuple[sympy.Symbol, ...]) -> dict[sympy.Symbol, list[sympy.Expr]]:
        """d residual / d task coordinate."""
        out = {}
        for s in task:
            d_t = self.t.diff(s)
            d_T = self.T.diff(s)
            out[s] = self._rows(-d_t, d_T.T * self.R_end)
        return out

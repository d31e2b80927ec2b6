"""Generic loop closure of a parallel mechanism declared by legs (seed sec. 3.2, IK steps 1-2).

Step 1, the closed vector chain of leg i: walking its joints from the base must reach the
platform's attachment frame,

    base_T_leg_i * prod_j (origin_j * motion_j(q, s)) = base_T_platform(p) * platform_T_B_i.

Step 2 splits it into Cartesian components: three position rows and three orientation
rows per leg,

    phi_pos = p_end - (P + R(p) b_i),
    phi_rot = vee(E - E^T) / 2,   E = (R(p) R_Bi)^T R_end,

where vee picks (E32, E13, E21); phi_rot is sin(angle) * axis of the residual rotation, zero
exactly when the orientations agree (away from half turns).  Step 3 (solving for the
unknowns) is closed-form where the leg allows it (:mod:`symkin.parallel.distance`) and
numerical otherwise (:func:`symkin.runtime.parallel.solve_closure`), using the implicit
Jacobians Phi_p, Phi_q, Phi_s of these equations:

    Phi_p pdot + Phi_q qdot + Phi_s sdot = 0.
"""

from __future__ import annotations

import sympy

from symkin.kinematics.chain import Frame
from symkin.parallel.legs import LegChain


def leg_residual(platform: Frame, chain: LegChain) -> list[sympy.Expr]:
    """The six closure equations of one leg (position rows, then orientation rows)."""
    target_R = sympy.Matrix(platform.R) * sympy.Matrix(chain.attachment.R)
    target_p = sympy.Matrix(platform.p) + sympy.Matrix(platform.R) * sympy.Matrix(chain.attachment.p)
    position = sympy.Matrix(chain.end.p) - target_p
    E = target_R.T * sympy.Matrix(chain.end.R)
    rotation = [(E[2, 1] - E[1, 2]) / 2, (E[0, 2] - E[2, 0]) / 2, (E[1, 0] - E[0, 1]) / 2]
    return list(position) + rotation

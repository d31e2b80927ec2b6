"""Task-space coordinates of the TCP and the rows of the task Jacobian (seed sec. 4, "Jacobian Matrix").

Components:

* ``x``, ``y``, ``z`` - TCP position in the base frame (m);
* ``roll``, ``pitch``, ``yaw`` - Z-Y-X Euler angles of base_R_tcp, R = Rz(yaw) Ry(pitch) Rx(roll)
  (rad); their Jacobian rows are the partial derivatives, as in the seed's J for the UR10e,
  and are singular at pitch = +-pi/2;
* ``wx``, ``wy``, ``wz`` - angular velocity of the TCP in the base frame (rad/s); these are
  velocity components with no coordinate, taken from the geometric Jacobian, so that
  tau = J^T [f; n] holds for a wrench (seed eq. 8.35).

``pose`` is ``[x, y, z, wx, wy, wz]``: the geometric Jacobian, the usual choice for 6-DoF
arms; ``position`` is ``[x, y, z]``.
"""

from __future__ import annotations

import sympy

from symkin.errors import DerivationError
from symkin.kinematics.chain import Frame

POSITION = {"x": 0, "y": 1, "z": 2}
ANGULAR_VELOCITY = {"wx": 0, "wy": 1, "wz": 2}
EULER = ("roll", "pitch", "yaw")

UNITS = {"x": "m", "y": "m", "z": "m", "roll": "rad", "pitch": "rad", "yaw": "rad",
         "wx": "rad/s", "wy": "rad/s", "wz": "rad/s"}


def euler_zyx(R: sympy.Matrix) -> dict[str, sympy.Expr]:
    """Z-Y-X Euler angles of a rotation matrix (atan2 forms, valid for |pitch| < pi/2)."""
    return {
        "roll": sympy.atan2(R[2, 1], R[2, 2]),
        "pitch": sympy.atan2(-R[2, 0], sympy.sqrt(R[2, 1] ** 2 + R[2, 2] ** 2)),
        "yaw": sympy.atan2(R[1, 0], R[0, 0]),
    }


def coordinates(components: tuple[str, ...], tcp: Frame) -> sympy.ImmutableMatrix:
    """The task-space coordinate vector p = f(q) (seed eq. 8.5).

    Raises:
        DerivationError: if a component is an angular velocity (it has no coordinate).
    """
    angles = euler_zyx(sympy.Matrix(tcp.R)) if any(c in EULER for c in components) else {}
    values = []
    for c in components:
        if c in POSITION:
            values.append(tcp.p[POSITION[c]])
        elif c in EULER:
            values.append(angles[c])
        else:
            raise DerivationError(f"task-space component '{c}' is an angular velocity and has no coordinate; "
                                  "declare the task space with roll/pitch/yaw to get orientation coordinates")
    return sympy.ImmutableMatrix(values)


def jacobian_rows(components: tuple[str, ...], geometric: sympy.Matrix, tcp: Frame,
                  q: tuple[sympy.Symbol, ...]) -> sympy.ImmutableMatrix:
    """Rows of the task Jacobian J = d(task)/dq (m x n).

    Position rows are the linear rows of the geometric Jacobian (for the TCP origin they
    equal dp/dq exactly); angular-velocity rows are its angular rows; Euler-angle rows are
    partial derivatives of the Euler angles.
    """
    angles = euler_zyx(sympy.Matrix(tcp.R)) if any(c in EULER for c in components) else {}
    rows = []
    for c in components:
        if c in POSITION:
            rows.append(list(geometric.row(POSITION[c])))
        elif c in ANGULAR_VELOCITY:
            rows.append(list(geometric.row(3 + ANGULAR_VELOCITY[c])))
        else:
            rows.append([sympy.diff(angles[c], qi) for qi in q])
    return sympy.ImmutableMatrix(rows)

"""Exact rotation matrices and homogeneous transforms (seed sec. 3: ^iR_j and ^iT_j).

Shared by the model builder (rotated inertia tensors), the kinematics and the parallel
mechanisms (loop closure, platform inertia).
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy

#: A 3-vector of exact expressions (an axis, a position, a centre of mass).
Vec3 = tuple[sympy.Expr, sympy.Expr, sympy.Expr]


def principal_axis(axis: Vec3) -> tuple[int, int] | None:
    """(index, sign) if ``axis`` is +-x, +-y or +-z, else None."""
    nonzero = [(i, c) for i, c in enumerate(axis) if c != 0]
    if len(nonzero) == 1 and nonzero[0][1] in (1, -1):
        return nonzero[0][0], int(nonzero[0][1])
    return None


#: Significant digits of the cosine and sine of a numeric angle: products of a few dozen such
#: numbers keep far more than the 17 digits a double literal prints.
CONSTANT_TRIG_DIGITS = 30


def cos_sin(angle: sympy.Expr) -> tuple[sympy.Expr, sympy.Expr]:
    """(cos, sin) of ``angle``: exact where sympy evaluates them (0, pi/2, pi/3, ...) or the angle is
    symbolic (a joint coordinate, a parameter, pi/7); for a plain number (a decimal from a file) each is
    one evaluation to :data:`CONSTANT_TRIG_DIGITS` digits, a number rather than cos(20679/10000): a chain
    of constant frames then composes to numbers instead of growing products of unevaluated trig, whose
    sign queries sympy answers by ever longer evaluations (issue 29: minutes for a stock URDF)."""
    c, s = sympy.cos(angle), sympy.sin(angle)
    if angle.is_Number and (isinstance(c, sympy.cos) or isinstance(s, sympy.sin)):
        return c.evalf(CONSTANT_TRIG_DIGITS), s.evalf(CONSTANT_TRIG_DIGITS)
    return c, s


def rotation_matrix(axis: Vec3, angle: sympy.Expr) -> sympy.Matrix:
    """Rotation by ``angle`` about the unit ``axis`` (right hand).

    Principal axes give the elementary matrices (e.g. the seed's rotation about z);
    any other axis uses Rodrigues' formula R = I + sin(a) K + (1 - cos(a)) K^2.  The cosine and
    sine of an angle given as a plain number (a URDF's rpy such as -2.0679) are evaluated once,
    to :data:`CONSTANT_TRIG_DIGITS` digits (:func:`cos_sin`).
    """
    c, s = cos_sin(angle)
    principal = principal_axis(axis)
    if principal is not None:
        index, sign = principal
        s = sign * s
        if index == 0:
            return sympy.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])
        if index == 1:
            return sympy.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        return sympy.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    kx, ky, kz = axis
    k = sympy.Matrix([[0, -kz, ky], [kz, 0, -kx], [-ky, kx, 0]])
    return sympy.eye(3) + s * k + (1 - c) * (k * k)


def homogeneous(rotation: sympy.Matrix, position: sympy.Matrix) -> sympy.ImmutableMatrix:
    """The 4x4 transform [[R, p], [0, 1]] (seed: homogeneous transformation matrix)."""
    top = rotation.row_join(position)
    return sympy.ImmutableMatrix(top.col_join(sympy.Matrix([[0, 0, 0, 1]])))


def skew(v: Sequence[sympy.Expr] | sympy.Matrix) -> sympy.Matrix:
    """[v]x, the matrix of the cross product: [v]x w = v x w."""
    return sympy.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

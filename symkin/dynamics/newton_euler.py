"""Symbolic recursive Newton-Euler inverse dynamics of a serial chain (seed sec. 4.4, "Iterative Approach").

The Lagrangian route (:mod:`symkin.dynamics.lagrange`) differentiates M(q): the Coriolis
vector from Christoffel symbols costs O(n^3) terms.  The recursive Newton-Euler algorithm
(Luh, Walker and Paul 1980; in the spatial-vector form of Featherstone, *Rigid Body
Dynamics Algorithms*, 2008, sec. 5.3, table 5.1) gives tau = M qdd + V + G in O(n):

1. outward, for each link i with parent p (the base for the first)::

       v_i = X_i v_p + S_i qd_i
       a_i = X_i a_p + S_i qdd_i + v_i x S_i qd_i,      a_0 = (0, -g)

   (gravity enters as an upward acceleration of the base);
2. per link, the net spatial force f_i = I_i a_i + v_i x* I_i v_i;
3. inward: tau_i = S_i . f_i, f_p += X_i^T f_i.

Every link i has its own *joint frame* F_i: the model's joint frame of joint i moved by the
joint (``before * Motion(q_i)``), so the joint axis passes through the origin of F_i along
the constant unit vector z_i of the model, and S_i = (z_i, 0) for a revolute and (0, z_i)
for a prismatic joint, constant.  The transform from F_p to F_i is the constant
``after_p * before_i`` (the base's fixed operations for the first joint) followed by the
joint motion: rotation E_i = (C_R Rot(z_i, q_i))^T and origin r_i = C_p (+ C_R z_i q_i if
prismatic) in F_p coordinates, so only sin(q_i) and cos(q_i) enter each step.  Spatial
vectors are (angular, linear) pairs of 3-vectors at the origin of their frame, in its
coordinates:

* motion transform  X (w, v) = (E w, E (v - r x w));
* force transform   X^T (n, f) = (E^T n + r x E^T f, E^T f);
* cross products    (w, v) x (w', v') = (w x w', w x v' + v x w'),
                    (w, v) x* (n, f)  = (w x n + v x f, w x f);
* rigid-body inertia of mass m, first moment h = m c and rotational inertia J about the
  origin (J = I_c - m [c]^2, parallel axes):  I (w, v) = (J w + h x v, m v - h x w).

The bodies of a link (point masses and rigid bodies with full inertia tensors, given in the
link frame) are summed into one spatial inertia in F_i with the constant ``after_i``
transform.  Everything is a SymEngine expression; the caller binds the results into a
:class:`~symkin.dynamics.program.Program`, whose CSE keeps the O(n) sharing.  Terms that
are zero are never built: no velocity pass without qd, no acceleration term without qdd,
no gravity term without gravity.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import symengine as se
import sympy

from symkin.dynamics.program import cross, dot, mat_vec, se_matrix, se_vector
from symkin.geometry import rotation_matrix
from symkin.model import coordinates
from symkin.model.schema import JointType, Model, Op, Rotation, Translation

Vec = list[se.Basic]
Spatial = tuple[Vec, Vec]


@dataclass(frozen=True)
class SpatialInertia:
    """A rigid body's inertia about the origin of its frame: mass m, first moment h = m c, rotational J."""

    mass: se.Basic
    moment: Vec
    rotational: list[Vec]

    def times(self, v: Spatial) -> Spatial:
        """I (w, v) = (J w + h x v, m v - h x w)."""
        w, lin = v
        n = [a + b for a, b in zip(mat_vec(self.rotational, w), cross(self.moment, lin))]
        f = [self.mass * a - b for a, b in zip(lin, cross(self.moment, w))]
        return n, f


@dataclass(frozen=True)
class Link:
    """One joint and the link it moves, in the joint frame F_i (see the module docstring).

    Attributes:
        type: revolute or prismatic.
        axis: the constant unit joint axis z_i in F_i.
        rotation: E_i, F_p coordinates -> F_i coordinates (3x3 rows, functions of q_i).
        origin: r_i, the origin of F_i in F_p coordinates.
        inertia: the bodies of the link in F_i, or None if it has neither mass nor inertia.
    """

    type: JointType
    axis: Vec
    rotation: list[Vec]
    origin: Vec
    inertia: SpatialInertia | None


def _compose(ops: Sequence[Op], R: sympy.Matrix, p: sympy.Matrix) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(R, p) of the frame reached from (R, p) by the fixed operations ``ops`` (moving frame, left to right)."""
    for op in ops:
        if isinstance(op, Rotation):
            R = R * rotation_matrix(op.axis, op.angle)
        else:
            assert isinstance(op, Translation)
            p = p + R * sympy.Matrix(op.vector)
    return R, p


def _link_inertia(model: Model, link: str, R: sympy.Matrix, p: sympy.Matrix) -> SpatialInertia | None:
    """The bodies on ``link`` summed into F_i, where the link frame has rotation R and origin p.

    J = sum_b R I_b R^T + m_b ([c_b]^T [c_b]) with c_b = p + R com_b (parallel-axis theorem).
    """
    mass, moment, rotational = sympy.Integer(0), sympy.zeros(3, 1), sympy.zeros(3, 3)
    found = False
    for body in model.bodies:
        if body.link != link or (body.mass == 0 and body.is_point_mass):
            continue
        found = True
        c = p + R * sympy.Matrix(body.com)
        mass += body.mass
        moment += body.mass * c
        rotational += R * sympy.Matrix(body.inertia) * R.T
        rotational += body.mass * ((c.T * c)[0, 0] * sympy.eye(3) - c * c.T)
    if not found:
        return None
    return SpatialInertia(se.sympify(mass), se_vector(moment), se_matrix(rotational))


def chain_links(model: Model) -> tuple[Link, ...]:
    """The links of a serial ``model`` in their joint frames, base to tip."""
    eye, zero = sympy.eye(3), sympy.zeros(3, 1)
    R_prev, p_prev = _compose(model.base, eye, zero)  # F_0 = base frame, then the base's fixed operations
    links = []
    for joint, q in zip(model.joints, coordinates.symbols(model, "q")):
        C_R, C_p = _compose(joint.before, R_prev, p_prev)
        amount = q + joint.offset
        axis = sympy.Matrix(joint.axis)
        if joint.type is JointType.REVOLUTE:
            R, origin = C_R * rotation_matrix(joint.axis, amount), C_p
        else:
            R, origin = C_R, C_p + C_R * axis * amount
        after_R, after_p = _compose(joint.after, eye, zero)
        links.append(Link(joint.type, se_vector(axis), se_matrix(R.T), se_vector(origin),
                          _link_inertia(model, joint.link, after_R, after_p)))
        R_prev, p_prev = after_R, after_p
    return tuple(links)


def _add(u: Vec, v: Vec) -> Vec:
    return [a + b for a, b in zip(u, v)]


def _motion_transform(link: Link, v: Spatial) -> Spatial:
    """X (w, v) = (E w, E (v - r x w))."""
    w, lin = v
    return mat_vec(link.rotation, w), mat_vec(link.rotation, [a - b for a, b in zip(lin, cross(link.origin, w))])


def _force_transform(link: Link, f: Spatial) -> Spatial:
    """X^T (n, f) = (E^T n + r x E^T f, E^T f)."""
    n, lin = f
    Et = [[link.rotation[r][c] for r in range(3)] for c in range(3)]
    f_parent = mat_vec(Et, lin)
    return _add(mat_vec(Et, n), cross(link.origin, f_parent)), f_parent


def _scaled_axis(link: Link, amount: se.Basic) -> Spatial:
    """S_i amount."""
    zero = [se.Integer(0)] * 3
    scaled = [c * amount for c in link.axis]
    return (scaled, zero) if link.type is JointType.REVOLUTE else (zero, scaled)


def _is_zero(v: Spatial) -> bool:
    return all(c == 0 for part in v for c in part)


def inverse_dynamics(links: Sequence[Link], qd: Sequence[se.Basic] | None, qdd: Sequence[se.Basic] | None,
                     gravity: Sequence[se.Basic] | None) -> list[se.Basic]:
    """tau = M qdd + V + G by the recursion of the module docstring.

    Args:
        links: :func:`chain_links`.
        qd, qdd: joint velocities and accelerations, or None where zero.
        gravity: the gravity vector in the base frame, or None.

    Returns:
        The joint torques (forces for prismatic joints), without friction.
    """
    zero = [se.Integer(0)] * 3
    v: Spatial = (zero, zero)
    a: Spatial = (zero, [-g for g in gravity] if gravity is not None else zero)
    forces: list[Spatial] = []
    for i, link in enumerate(links):
        v = _motion_transform(link, v)
        a = _motion_transform(link, a)
        if qd is not None:
            Sqd = _scaled_axis(link, qd[i])
            # v_i x S qd = (X v_p) x S qd, since S qd x S qd = 0.
            w, lin = v
            a = (_add(a[0], cross(w, Sqd[0])), _add(a[1], _add(cross(w, Sqd[1]), cross(lin, Sqd[0]))))
            v = (_add(v[0], Sqd[0]), _add(v[1], Sqd[1]))
        if qdd is not None:
            Sqdd = _scaled_axis(link, qdd[i])
            a = (_add(a[0], Sqdd[0]), _add(a[1], Sqdd[1]))
        if link.inertia is None:
            forces.append((zero, zero))
            continue
        f = link.inertia.times(a)
        if qd is not None:
            w, lin = v
            n_v, f_v = link.inertia.times(v)
            f = (_add(f[0], _add(cross(w, n_v), cross(lin, f_v))), _add(f[1], cross(w, f_v)))
        forces.append(f)
    tau: list[se.Basic] = [se.Integer(0)] * len(links)
    carried: Spatial = (zero, zero)
    for i in reversed(range(len(links))):
        link = links[i]
        f = (_add(forces[i][0], carried[0]), _add(forces[i][1], carried[1]))
        tau[i] = dot(link.axis, f[0] if link.type is JointType.REVOLUTE else f[1])
        carried = _force_transform(link, f) if i > 0 and not _is_zero(f) else (zero, zero)
    return tau


def _skew(v: Vec) -> list[Vec]:
    zero = se.Integer(0)
    return [[zero, -v[2], v[1]], [v[2], zero, -v[0]], [-v[1], v[0], zero]]


def _mat_mul(A: list[Vec], B: list[Vec]) -> list[Vec]:
    return [[dot(row, [B[k][c] for k in range(3)]) for c in range(3)] for row in A]


def _to_parent(link: Link, inertia: SpatialInertia) -> SpatialInertia:
    """X^T I X: ``inertia`` in F_i expressed about the origin of F_p, in F_p coordinates.

    m' = m, h' = E^T h + m r, J' = E^T J E - [E^T h][r] - [r][E^T h] - m [r]^2.
    """
    E = link.rotation
    Et = [[E[r][c] for r in range(3)] for c in range(3)]
    h = mat_vec(Et, inertia.moment)
    r = link.origin
    J = _mat_mul(Et, _mat_mul(inertia.rotational, E))
    hr, rh, rr = _mat_mul(_skew(h), _skew(r)), _mat_mul(_skew(r), _skew(h)), _mat_mul(_skew(r), _skew(r))
    J = [[J[a][b] - hr[a][b] - rh[a][b] - inertia.mass * rr[a][b] for b in range(3)] for a in range(3)]
    return SpatialInertia(inertia.mass, [a + inertia.mass * b for a, b in zip(h, r)], J)


def _sum(a: SpatialInertia | None, b: SpatialInertia | None) -> SpatialInertia | None:
    if a is None or b is None:
        return a or b
    return SpatialInertia(a.mass + b.mass, _add(a.moment, b.moment),
                          [_add(x, y) for x, y in zip(a.rotational, b.rotational)])


def mass_matrix(links: Sequence[Link]) -> list[list[se.Basic]]:
    """M(q) by the composite-rigid-body algorithm (Featherstone sec. 6.2, table 6.2)."""
    n = len(links)
    composite: list[SpatialInertia | None] = [link.inertia for link in links]
    for i in reversed(range(1, n)):
        if composite[i] is not None:
            composite[i - 1] = _sum(composite[i - 1], _to_parent(links[i], composite[i]))
    M = [[se.Integer(0)] * n for _ in range(n)]
    for i in range(n):
        if composite[i] is None:
            continue
        f = composite[i].times(_scaled_axis(links[i], se.Integer(1)))
        for j in reversed(range(i + 1)):
            link = links[j]
            M[i][j] = M[j][i] = dot(link.axis, f[0] if link.type is JointType.REVOLUTE else f[1])
            if j > 0:
                f = _force_transform(link, f)
    return M

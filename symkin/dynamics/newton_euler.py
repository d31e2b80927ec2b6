"""Symbolic Newton-Euler dynamics of a serial chain: recursive inverse dynamics, composite-rigid-body M.

The Lagrangian route (:mod:`symkin.dynamics.lagrange`) differentiates M(q): the Coriolis
vector from Christoffel symbols costs O(n^3) terms.  The recursive Newton-Euler algorithm
(seed sec. 4.4, "Iterative Approach"; Luh, Walker and Paul 1980; Craig, *Introduction to
Robotics*, sec. 6.5) gives tau = M qdd + V + G in O(n) operations.

Frames.  Every link i has its *joint frame* F_i: the model's joint frame of joint i moved
by the joint (``before * Motion(q_i)``), fixed to link i.  The joint axis passes through
the origin of F_i along the constant unit vector z_i of the model.  The transform from the
parent frame F_p to F_i is the constant ``after_p * before_i`` (the base's fixed
operations for the first joint) followed by the joint motion: rotation E_i = (C_R
Rot(z_i, q_i))^T from F_p to F_i coordinates and origin r_i = C_p (+ C_R z_i q_i if
prismatic) in F_p coordinates, so each step involves only sin(q_i) and cos(q_i).  The
bodies of a link (point masses and rigid bodies with full inertia tensors, given in the
link frame) are summed into one :class:`SpatialInertia` in F_i with the constant
``after_i`` transform: mass m, first moment h = m c and rotational inertia J about the
origin (J = sum R I_c R^T - m [c]^2, parallel axes).

Inverse dynamics (:func:`inverse_dynamics`), everything in F_i coordinates:

1. outward, with w_0 = dw_0 = 0 and a_0 = -g (gravity as an upward acceleration of the base)::

       a_i  = E_i (a_p + dw_p x r_i + w_p x (w_p x r_i))      acceleration of the origin of F_i
       w_i  = E_i w_p + z_i qd_i                               (revolute)
       dw_i = E_i dw_p + (E_i w_p) x z_i qd_i + z_i qdd_i
       a_i += 2 w_i x z_i qd_i + z_i qdd_i                     (prismatic; w_i = E_i w_p, dw_i = E_i dw_p)

2. per link, the force and the moment about the origin that move its bodies::

       f_i = m a_i + dw_i x h + w_i x (w_i x h),   n_i = J dw_i + w_i x J w_i + h x a_i

3. inward: f_p += E_i^T f_i, n_p += E_i^T n_i + r_i x E_i^T f_i; tau_i = z_i . n_i
   (revolute) or z_i . f_i (prismatic).

The mass matrix (:func:`mass_matrix`) comes from the composite-rigid-body algorithm
(Featherstone, *Rigid Body Dynamics Algorithms*, 2008, sec. 6.2): composite inertias
I^c_p += X_i^T I^c_i X_i inward, then M_ij = S_j . X^T ... X^T I^c_i S_i.  Gravity
(:func:`gravity_torques`) is the Newton-Euler pass at rest, which reduces to the composite
masses and first moments: G_i = z_i . (h^c_i x a_i).

Everything is a SymEngine expression; the caller binds the results into a
:class:`~symkin.dynamics.program.Program`, whose CSE keeps the O(n) sharing.  Terms that
are zero are never built: no velocity terms without qd, no acceleration terms without
qdd, no gravity without gravity.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import symengine as se
import sympy

from symkin.dynamics.program import cross, dot, mat_vec, se_matrix, se_vector
from symkin.model import coordinates
from symkin.kinematics.chain import MovingFrame
from symkin.model import joint_kinds, tree
from symkin.model.schema import Joint, JointType, Model, Op

Vec = list[se.Basic]
#: A pair of 3-vectors: (angular, linear) motion or (moment, force).
Spatial = tuple[Vec, Vec]


def _add(u: Vec, v: Vec) -> Vec:
    return [a + b for a, b in zip(u, v)]


def _transpose(A: list[Vec]) -> list[Vec]:
    return [[A[r][c] for r in range(3)] for c in range(3)]


def _skew(v: Vec) -> list[Vec]:
    zero = se.Integer(0)
    return [[zero, -v[2], v[1]], [v[2], zero, -v[0]], [-v[1], v[0], zero]]


def _mat_mul(A: list[Vec], B: list[Vec]) -> list[Vec]:
    return [[dot(row, [B[k][c] for k in range(3)]) for c in range(3)] for row in A]


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
        armature: the drive's reflected rotor inertia N^2 J_m on the joint (0 without an actuator):
            M_ii += armature, tau_i += armature qdd_i (:class:`~symkin.model.schema.Actuator`).
        parent: the index of the parent link, -1 for the base (:mod:`symkin.model.tree`).
    """

    type: JointType
    axis: Vec
    rotation: list[Vec]
    origin: Vec
    inertia: SpatialInertia | None
    armature: se.Basic = se.Integer(0)
    #: the index of the parent link (-1: the base); the previous link in a chain, any earlier one in a tree.
    parent: int = -1


def _compose(ops: Sequence[Op], R: sympy.Matrix, p: sympy.Matrix) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(R, p) of the frame reached from (R, p) by the fixed operations ``ops`` (moving frame, left to right)."""
    frame = MovingFrame(R, p)
    frame.apply(ops)
    return frame.rotation(), frame.p


def link_frame(joint: Joint) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(R, p): the rotation and origin of the joint's link frame in its joint frame F_i (the ``after`` operations)."""
    return _compose(joint.after, sympy.eye(3), sympy.zeros(3, 1))


def _link_inertia(model: Model, link: str, R: sympy.Matrix, p: sympy.Matrix) -> SpatialInertia | None:
    """The bodies on ``link`` summed into F_i, where the link frame has rotation R and origin p.

    J = sum_b R I_b R^T + m_b (c_b . c_b 1 - c_b c_b^T) with c_b = p + R com_b (parallel-axis theorem).
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
    """The links of a serial ``model`` in their joint frames, parents first (a chain or a tree)."""
    eye, zero = sympy.eye(3), sympy.zeros(3, 1)
    base = _compose(model.base, eye, zero)  # F_0 = base frame, then the base's fixed operations
    links = []
    # the reflected inertia of drives without a rotor body of their own (symkin.model.rotors)
    armature = {a.joint: se.sympify(a.reflected_inertia) for a in model.actuators if not a.gyroscopic}
    parents = tree.parent_indices(model)
    afters: list[tuple[sympy.Matrix, sympy.Matrix]] = []  # each link's frame in its joint frame
    for joint, q, parent in zip(model.joints, coordinates.joint_values(model, "q"), parents):
        R_prev, p_prev = base if parent < 0 else afters[parent]
        C_R, C_p = _compose(joint.before, R_prev, p_prev)
        R, origin = _compose((joint.motion(q + joint.offset),), C_R, C_p)
        axis = sympy.Matrix(joint.axis)
        after_R, after_p = link_frame(joint)
        links.append(Link(joint.type, se_vector(axis), se_matrix(R.T), se_vector(origin),
                          _link_inertia(model, joint.link, after_R, after_p),
                          armature.get(joint.name, se.Integer(0)), parent))
        afters.append((after_R, after_p))
    return tuple(links)


def _force_transform(link: Link, f: Spatial) -> Spatial:
    """X^T (n, f) = (E^T n + r x E^T f, E^T f)."""
    n, lin = f
    Et = _transpose(link.rotation)
    f_parent = mat_vec(Et, lin)
    return _add(mat_vec(Et, n), cross(link.origin, f_parent)), f_parent


def _motion_axis(link: Link) -> Spatial:
    """S_i: (z_i, 0) for a revolute joint, (0, z_i) for a prismatic one."""
    zero = [se.Integer(0)] * 3
    return joint_kinds.motion_subspace(link.type, link.axis, zero)


def _is_zero(v: Spatial) -> bool:
    return all(c == 0 for part in v for c in part)


def inverse_dynamics(links: Sequence[Link], qd: Sequence[se.Basic] | None, qdd: Sequence[se.Basic] | None,
                     gravity: Sequence[se.Basic] | None) -> list[se.Basic]:
    """tau = M qdd + V + G by the Luh-Walker-Paul recursion of the module docstring.

    Args:
        links: :func:`chain_links`.
        qd, qdd: joint velocities and accelerations, or None where zero (no velocity terms
            without qd, no acceleration terms without qdd).
        gravity: the gravity vector in the base frame, or None.

    Returns:
        The joint torques (forces for prismatic joints), without friction.
    """
    motions = link_motions(links, qd, qdd, gravity)
    zero = [se.Integer(0)] * 3
    wrenches = [(zero, zero) if link.inertia is None else body_wrench(link.inertia, motion)
                for link, motion in zip(links, motions)]
    return joint_torques(links, wrenches, qdd)


#: The angular velocity w, angular acceleration dw and acceleration a of a link's origin, in its frame.
Motion = tuple[Vec, Vec, Vec]


def link_motions(links: Sequence[Link], qd: Sequence[se.Basic] | None, qdd: Sequence[se.Basic] | None,
                 gravity: Sequence[se.Basic] | None) -> list[Motion]:
    """Step 1 of the module docstring: (w, dw, a) of every link, outward from the base (a_0 = -g)."""
    zero = [se.Integer(0)] * 3
    base_acc = [-g for g in gravity] if gravity is not None else zero
    motion: list[Motion] = []
    for i, link in enumerate(links):
        w, dw, acc = (zero, zero, base_acc) if link.parent < 0 else motion[link.parent]
        E, r = link.rotation, link.origin
        # The origin of F_i is a point of the parent link at r (moved along the axis if prismatic).
        acc = mat_vec(E, _add(acc, _add(cross(dw, r), cross(w, cross(w, r)))))
        w, dw = mat_vec(E, w), mat_vec(E, dw)
        # the joint's twist per unit rate (its kind's motion subspace): (z, 0) turning, (0, z) sliding
        turning, sliding = joint_kinds.motion_subspace(link.type, link.axis, zero)
        if qd is not None:  # dw += w x (w_j qd), a += 2 w x (v_j qd) (Coriolis), w += w_j qd
            turned, slid = [c * qd[i] for c in turning], [c * qd[i] for c in sliding]
            dw = _add(dw, cross(w, turned))
            acc = _add(acc, [2 * c for c in cross(w, slid)])
            w = _add(w, turned)
        if qdd is not None:
            dw = _add(dw, [c * qdd[i] for c in turning])
            acc = _add(acc, [c * qdd[i] for c in sliding])
        motion.append((w, dw, acc))
    return motion


def body_wrench(body: SpatialInertia, motion: Motion) -> Spatial:
    """Step 2: the moment about the origin and the force that move ``body`` (in its link's frame) with ``motion``."""
    w, dw, acc = motion
    h, J = body.moment, body.rotational
    f = _add([body.mass * a for a in acc], _add(cross(dw, h), cross(w, cross(w, h))))
    n = _add(_add(mat_vec(J, dw), cross(w, mat_vec(J, w))), cross(h, acc))
    return n, f


def joint_torques(links: Sequence[Link], wrenches: Sequence[Spatial], qdd: Sequence[se.Basic] | None
                  ) -> list[se.Basic]:
    """Step 3: each link's wrench carried inward, tau_i = z_i . n_i (revolute) or z_i . f_i (prismatic), plus the
    drive's armature qdd_i where ``qdd`` is given."""
    zero = [se.Integer(0)] * 3
    tau: list[se.Basic] = [se.Integer(0)] * len(links)
    carried: list[Spatial] = [(zero, zero) for _ in links]  # what the children pass to each link
    for i in reversed(range(len(links))):
        link = links[i]
        total = (_add(wrenches[i][0], carried[i][0]), _add(wrenches[i][1], carried[i][1]))
        tau[i] = dot(link.axis, joint_kinds.worked_part(link.type, total))
        if qdd is not None and link.armature != 0:
            tau[i] += link.armature * qdd[i]
        if link.parent >= 0 and not _is_zero(total):
            moved = _force_transform(link, total)
            p = link.parent
            carried[p] = moved if _is_zero(carried[p]) else (_add(carried[p][0], moved[0]),
                                                             _add(carried[p][1], moved[1]))
    return tau


def _moment_to_parent(link: Link, mass: se.Basic, moment: Vec) -> Vec:
    """The first moment h of a body in F_i about the origin of F_p, in F_p coordinates: E^T h + m r."""
    return [a + mass * b for a, b in zip(mat_vec(_transpose(link.rotation), moment), link.origin)]


def _to_parent(link: Link, inertia: SpatialInertia) -> SpatialInertia:
    """X^T I X: ``inertia`` in F_i expressed about the origin of F_p, in F_p coordinates.

    m' = m, h' = E^T h + m r, J' = E^T J E - [E^T h][r] - [r][E^T h] - m [r]^2.
    """
    E = link.rotation
    Et = _transpose(E)
    h = mat_vec(Et, inertia.moment)
    r = link.origin
    J = _mat_mul(Et, _mat_mul(inertia.rotational, E))
    hr, rh, rr = _mat_mul(_skew(h), _skew(r)), _mat_mul(_skew(r), _skew(h)), _mat_mul(_skew(r), _skew(r))
    J = [[J[a][b] - hr[a][b] - rh[a][b] - inertia.mass * rr[a][b] for b in range(3)] for a in range(3)]
    return SpatialInertia(inertia.mass, _moment_to_parent(link, inertia.mass, inertia.moment), J)


def _sum(a: SpatialInertia | None, b: SpatialInertia | None) -> SpatialInertia | None:
    if a is None or b is None:
        return a or b
    return SpatialInertia(a.mass + b.mass, _add(a.moment, b.moment),
                          [_add(x, y) for x, y in zip(a.rotational, b.rotational)])


def _composites(links: Sequence[Link], rotational: bool) -> list[SpatialInertia | None]:
    """The composite inertia of each link and everything it carries, in its frame F_i.

    With ``rotational=False`` only the mass and the first moment are summed (the
    rotational inertia is left as it is): all that gravity needs.
    """
    composite: list[SpatialInertia | None] = [link.inertia for link in links]
    for i in reversed(range(len(links))):
        child = composite[i]
        if child is None or links[i].parent < 0:
            continue
        if rotational:
            moved = _to_parent(links[i], child)
        else:
            moved = SpatialInertia(child.mass, _moment_to_parent(links[i], child.mass, child.moment),
                                   [[se.Integer(0)] * 3 for _ in range(3)])
        composite[links[i].parent] = _sum(composite[links[i].parent], moved)
    return composite


def gravity_torques(links: Sequence[Link], gravity: Sequence[se.Basic]) -> list[se.Basic]:
    """G(q): the Newton-Euler torques at rest (qd = qdd = 0).

    At rest every link has the same acceleration -g (in F_i: a_i = E_i a_p), and the
    inward pass sums the forces m_b a and moments h_b x a of the bodies beyond joint i into
    those of their composite body (mass m^c_i, first moment h^c_i, as in the
    composite-rigid-body algorithm): G_i = z_i . (h^c_i x a_i) for a revolute joint,
    z_i . m^c_i a_i for a prismatic one.
    """
    composite = _composites(links, rotational=False)
    accelerations: list[Vec] = []
    G = []
    for link, body in zip(links, composite):
        acc = mat_vec(link.rotation, [-g for g in gravity] if link.parent < 0 else accelerations[link.parent])
        accelerations.append(acc)
        if body is None:
            G.append(se.Integer(0))
        else:  # the composite's weight wrench (moment h^c x a, force m^c a) against the joint's motion
            G.append(dot(link.axis, joint_kinds.worked_part(link.type, (cross(body.moment, acc),
                                                                        [body.mass * a for a in acc]))))
    return G


def mass_matrix(links: Sequence[Link]) -> list[list[se.Basic]]:
    """M(q) by the composite-rigid-body algorithm (Featherstone sec. 6.2, table 6.2)."""
    n = len(links)
    composite = _composites(links, rotational=True)
    M = [[se.Integer(0)] * n for _ in range(n)]
    for i in range(n):
        body = composite[i]
        if body is None:
            continue
        f = body.times(_motion_axis(links[i]))
        j = i
        while j >= 0:  # i and its ancestors; M_ij = 0 for a j on another branch
            link = links[j]
            M[i][j] = M[j][i] = dot(link.axis, joint_kinds.worked_part(link.type, f))
            if link.parent >= 0:
                f = _force_transform(link, f)
            j = link.parent
    for i, link in enumerate(links):
        M[i][i] += link.armature
    return M

"""The mass distribution of a parallel mechanism, split by what moves it (sympy, exact).

With the rods lumped at their ends (:class:`~symkin.model.schema.ParallelBodies`), every
mass of a distance-form mechanism (:mod:`symkin.parallel.distance`) moves either with one
actuated variable q_i (the actuated link, the rod's share at C_i, the rotor) or with the
platform (the platform body, the rods' shares at B_i).  The kinetic and potential energy
separate accordingly:

    k = 1/2 qd^T M_a(q) qd + 1/2 pd^T M_p(p) pd,        u = u_a(q) + u_p(p),

* M_a is diagonal: leg i's actuator side turns (or slides) about the fixed axis of its first
  moving joint, M_a,ii = m |dc/dq_i|^2 + w^T (R I R^T) w + m_C |dC/dq_i|^2 + n^2 J_rotor;
* M_p is the platform's spatial inertia in the task coordinates p = (position, roll, pitch,
  yaw): with the mass m, the first moment h and the inertia I_o about the platform origin
  (all platform-side masses summed, parallel-axis theorem; platform axes), v_o = d(position)/dt
  and the angular velocity in platform axes w_b = E_b d(angles)/dt,

      k_p = 1/2 m |v_o|^2 + v_o . R (w_b x h) + 1/2 w_b^T I_o w_b,

  so M_p = [[m 1, -R [h]x E_b], [.., E_b^T I_o E_b]] (constant, m 1, for a translational
  platform); a platform moving in fewer coordinates (planar, spherical, Schoenflies) takes the
  rows and columns of its own: v_o = J_v pd and w_b = W pd, M_p = m J_v^T J_v + C + C^T + W^T I_o W
  with C = -J_v^T R [h]x W;
* u = -g . (sum of mass times centre of mass), the same split.

This is what makes the Lagrangian of the closed chain reducible through the task Jacobian
(:mod:`symkin.parallel.dynamics`).

A spherical leg's distal link (between its last two joints) turns with a passive joint, but it carries
two axes whose directions are known without it: the middle axis C_i = w_i(q_i), turned by the actuator,
and the platform's axis B_i = v_i(p) = R(p) v_i0 (:mod:`symkin.parallel.distance`).  With w and v those
axes in the link's own frame (constant, at the constant angle alpha_i), the link's orientation is
R_d = W L^-1 with W = [C_i, B_i, C_i x B_i] and L = [w, v, w x v], exact on the assembled mechanism:
:class:`DistalLink` holds what its dynamics need (:mod:`symkin.parallel.distal`), and its potential
energy joins u as u_d(q, p) = -m g . R_d c_b.

A rod of fixed length L between C_i(q_i) and B_i(p) with its own inertia I_c across it (``rod: inertia:``,
a slender rod whose centre of mass lies at the fraction f of the way to B_i) is its lumped ends, which carry
its mass and centre of mass, plus the difference of the inertias, dI = I_c - m f (1 - f) L^2 (the ends' own
inertia about the centre of mass; dI < 0 for a real bar, -m L^2 / 6 for a uniform one): the kinetic energy
1/2 dI |w_perp|^2 of the rod's angular velocity across it, w_perp = d x dd/dt / L^2 with d = B_i - C_i (its
spin about its own axis carries no inertia).  :class:`SwingingRod` holds what its dynamics need
(:mod:`symkin.parallel.distal`); its potential is that of its ends.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy

from symkin.errors import DerivationError
from symkin.geometry import skew
from symkin.kinematics.chain import Frame
from symkin.model.schema import Body, Model, ParallelBodies
from symkin.parallel.distance import DistanceLeg, distal_axes
from symkin.parallel.inputs import task_symbols
from symkin.parallel.legs import LegChain, walk


@dataclass(frozen=True)
class DistalLink:
    """A spherical leg's distal link, turning about the centre of rotation (the base origin) with R_d = W L^-1.

    Attributes:
        q: the leg's actuated variable.
        C: the middle axis C_i(q_i) in the base frame (unit).
        B: the platform's axis B_i(p) in the base frame (unit).
        frame_inverse: L^-1, L = [w, v, w x v] (the two axes in the link frame).
        cosine: w . v = C . B, the cosine of the constant angle between the two axes.
        mass: the link's mass.
        com: its centre of mass in the link frame, from the centre of rotation.
        inertia: its inertia about the centre of rotation in the link frame.
    """

    q: sympy.Symbol
    C: sympy.ImmutableMatrix
    B: sympy.ImmutableMatrix
    frame_inverse: sympy.ImmutableMatrix
    cosine: sympy.Expr
    mass: sympy.Expr
    com: sympy.ImmutableMatrix
    inertia: sympy.ImmutableMatrix

    @property
    def rotation(self) -> sympy.Matrix:
        """R_d = W L^-1."""
        C, B = sympy.Matrix(self.C), sympy.Matrix(self.B)
        return sympy.Matrix.hstack(C, B, C.cross(B)) * sympy.Matrix(self.frame_inverse)


@dataclass(frozen=True)
class SwingingRod:
    """A leg's rod of fixed length between C_i(q_i) and B_i(p), its inertia beyond its lumped ends.

    Attributes:
        q: the leg's actuated variable.
        C: the rod's end C_i(q_i) in the base frame.
        B: its end B_i(p) at the platform, in the base frame.
        length_squared: L^2 = |B_i - C_i|^2, constant.
        inertia: dI = I_c - m f (1 - f) L^2, its moment of inertia across it beyond that of its ends.
    """

    q: sympy.Symbol
    C: sympy.ImmutableMatrix
    B: sympy.ImmutableMatrix
    length_squared: sympy.Expr
    inertia: sympy.Expr


@dataclass(frozen=True)
class Inertia:
    """The split mass distribution (see the module docstring).

    Attributes:
        actuator_diagonal: M_a,ii per leg, a function of q_i only.
        actuator_potential: u_a(q).
        platform_matrix: M_p(p), symmetric, one row per task coordinate.
        platform_potential: u_p(p).
        distal_links: the spherical legs' distal links, one per leg (none for other mechanisms).
        distal_potential: their potential energy u_d(q, p).
        rods: the legs' rods with an inertia of their own (``rod: inertia:``), one per leg, or none.
    """

    actuator_diagonal: tuple[sympy.Expr, ...]
    actuator_potential: sympy.Expr
    platform_matrix: sympy.ImmutableMatrix
    platform_potential: sympy.Expr
    distal_links: tuple[DistalLink, ...] = ()
    distal_potential: sympy.Expr = sympy.Integer(0)
    rods: tuple[SwingingRod, ...] = ()


def body_angular_velocity_matrix(model: Model) -> sympy.Matrix:
    """W with w_body = R^T w = W pd for R = Rz(yaw) Ry(pitch) Rx(roll): one column per task coordinate.

    w = yawd z + pitchd Rz y + rolld Rz Ry x, so R^T w = rolld x + pitchd Rx^T y + yawd Rx^T Ry^T z:
    E_b = [[1, 0, -sin(pitch)], [0, cos(roll), sin(roll) cos(pitch)], [0, -sin(roll), cos(roll) cos(pitch)]]
    maps d(roll, pitch, yaw)/dt to w_body.  W holds E_b's column for each angle the platform turns by
    (the others held at 0) and a zero column for each position coordinate.
    """
    values = dict(zip(model.task_space, task_symbols(model)))
    roll, pitch = values.get("roll", sympy.Integer(0)), values.get("pitch", sympy.Integer(0))
    E_b = sympy.Matrix([[1, 0, -sympy.sin(pitch)],
                        [0, sympy.cos(roll), sympy.sin(roll) * sympy.cos(pitch)],
                        [0, -sympy.sin(roll), sympy.cos(roll) * sympy.cos(pitch)]])
    angles = ("roll", "pitch", "yaw")
    return sympy.Matrix.hstack(*[E_b[:, angles.index(c)] if c in angles else sympy.zeros(3, 1)
                                 for c in model.task_space])


#: A body about a frame's origin: (mass m, first moment h = m c, inertia I_o about the origin), frame axes.
Triple = tuple[sympy.Expr, sympy.Matrix, sympy.Matrix]


def unit_triples() -> list[Triple]:
    """(m, h, I_o) with one standard parameter 1 and the others 0, in INERTIAL order
    (:data:`symkin.dynamics.parameter_names.INERTIAL`: m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)."""
    out: list[Triple] = [(sympy.Integer(1), sympy.zeros(3, 1), sympy.zeros(3, 3))]
    out += [(sympy.Integer(0), sympy.Matrix([int(k == axis) for k in range(3)]), sympy.zeros(3, 3))
            for axis in range(3)]
    for r, c in ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)):
        inertia = sympy.zeros(3, 3)
        inertia[r, c] = inertia[c, r] = 1
        out.append((sympy.Integer(0), sympy.zeros(3, 1), inertia))
    return out


def standard_values(triple: Triple) -> list[sympy.Expr]:
    """(m, h, I_o) as the ten standard parameters, in INERTIAL order."""
    m, h, I = triple
    return [m, h[0], h[1], h[2], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]


def about_origin(body: Body) -> Triple:
    """(m, h = m c, I_o = I_c + m (|c|^2 E - c c^T)): a body's mass, first moment and inertia about its
    frame origin (parallel-axis theorem)."""
    c = sympy.Matrix(body.com)
    return body.mass, body.mass * c, sympy.Matrix(body.inertia) + body.mass * (c.dot(c) * sympy.eye(3) - c * c.T)


def platform_side(model: Model, parts: list[tuple[sympy.Expr, sympy.Matrix, sympy.Matrix]], platform: Frame
                  ) -> tuple[sympy.ImmutableMatrix, sympy.Expr]:
    """M_p(p) and u_p(p) of masses (m, h, I_o) that move with the platform (see the module docstring): linear in them."""
    m = sum((part[0] for part in parts), sympy.Integer(0))
    h = sum((part[1] for part in parts), sympy.zeros(3, 1))
    I_o = sum((part[2] for part in parts), sympy.zeros(3, 3))
    position, platform_R = sympy.Matrix(platform.p), sympy.Matrix(platform.R)
    g = sympy.Matrix(model.gravity)
    potential = -g.dot(m * position + platform_R * h)
    J_v = position.jacobian(task_symbols(model))
    W = body_angular_velocity_matrix(model)
    coupling = -J_v.T * platform_R * skew(h) * W  # v_o . R (w_b x h) = -v_o . R [h]x w_b
    M = m * J_v.T * J_v + coupling + coupling.T + W.T * I_o * W
    # a platform that does not turn has a potential linear in p: expanded, as the DELTA's has always been emitted
    return sympy.ImmutableMatrix(M), sympy.expand(potential) if W.is_zero_matrix else potential


def point_mass(mass: sympy.Expr, point: sympy.Matrix) -> tuple[sympy.Expr, sympy.Matrix, sympy.Matrix]:
    """(m, h, I_o) of a point mass at ``point`` of the frame: (m, m b, m (|b|^2 E - b b^T))."""
    return about_origin(Body("point", mass, tuple(point), sympy.zeros(3, 3)))


def _platform(model: Model, bodies: ParallelBodies, legs: tuple[DistanceLeg, ...], platform: Frame
              ) -> tuple[sympy.ImmutableMatrix, sympy.Expr]:
    """M_p(p) and u_p(p) of the platform body and the rods' shares at the platform joints."""
    parts = [about_origin(bodies.platform)] if bodies.platform is not None else []
    share = bodies.rod_mass * bodies.rod_platform_fraction
    parts += [point_mass(share, leg.b) for leg in legs]
    return platform_side(model, parts, platform)


def actuated_frame(model: Model, bodies_link: bool, leg: DistanceLeg, chain: LegChain
                   ) -> tuple[sympy.Matrix, sympy.Matrix, sympy.Matrix]:
    """(R, o, w): the frame right after leg ``leg``'s actuated joint (its actuated link's frame) in the base frame,
    and the joint's angular velocity per unit rate (0 for a prismatic joint).

    Raises:
        DerivationError: the actuator is not the leg's first moving joint, so no link moves with it alone.
    """
    index = next(k for k, j in enumerate(leg.leg.joints) if j.active is not None)
    frame = walk(leg.leg, joints=slice(0, index + 1)).end
    if leg.actuator != "before" or (frame.p.free_symbols | frame.R.free_symbols) & _variables(leg, {leg.q}):
        fix = "remove 'bodies: actuated_link:' and lump its mass" if bodies_link else "it has no actuated link"
        raise DerivationError(
            f"model '{model.name}': leg '{leg.leg.name}' has no link moved by its actuator alone (the actuated "
            f"joint is not the first moving joint of the leg); {fix}")
    motion = next(m for m in chain.motions if m.variable == leg.q)
    w = sympy.Matrix(motion.direction) if motion.rotation else sympy.zeros(3, 1)
    return sympy.Matrix(frame.R), sympy.Matrix(frame.p), w


def elbow_mass_terms(model: Model, leg: DistanceLeg) -> tuple[sympy.Expr, sympy.Expr]:
    """(|dC_i/dq_i|^2, g . C_i): M_a,ii and -u_a,i of a unit mass at the rod's end C_i."""
    C = sympy.Matrix(leg.C)
    rate = sympy.diff(C, leg.q)
    return sympy.trigsimp(rate.dot(rate)), sympy.Matrix(model.gravity).dot(C)


def _actuator_side(model: Model, bodies: ParallelBodies, leg: DistanceLeg, chain: LegChain
                   ) -> tuple[sympy.Expr, sympy.Expr]:
    """(M_a,ii, u_a,i) of one leg: actuated link, rod share at C_i and rotor."""
    g = sympy.Matrix(model.gravity)
    q = leg.q
    inertia = bodies.gear_ratio ** 2 * bodies.rotor_inertia
    potential = sympy.Integer(0)
    C_share = bodies.rod_mass * (1 - bodies.rod_platform_fraction)
    elbow_inertia, elbow_height = elbow_mass_terms(model, leg)
    inertia += C_share * elbow_inertia
    potential += -C_share * elbow_height
    if bodies.actuated_link is not None:
        link = bodies.actuated_link
        R, origin, w = actuated_frame(model, True, leg, chain)
        c = origin + R * sympy.Matrix(link.com)
        v = sympy.diff(c, q)
        inertia += sympy.trigsimp(link.mass * v.dot(v) + (w.T * R * sympy.Matrix(link.inertia) * R.T * w)[0, 0])
        potential += -link.mass * g.dot(c)
    return inertia, potential


def distal_link(model: Model, link: Body, leg: DistanceLeg, chain: LegChain) -> DistalLink:
    """One spherical leg's distal link carrying the body ``link`` (see the module docstring)."""
    w, v = distal_axes(leg.leg)
    L = sympy.Matrix.hstack(w, v, w.cross(v))
    if L.det() == 0:
        raise DerivationError(f"model '{model.name}': leg '{leg.leg.name}' has its last two axes parallel, so they do "
                              "not fix its distal link's orientation; remove 'bodies: distal_link:'")
    # the link frame's origin lies on the middle axis C_i (it passes through the centre): at d w in the link frame
    origin, C = sympy.Matrix(chain.centres[-2]), sympy.Matrix(leg.C)
    d = sympy.simplify(origin.dot(C))
    if any(sympy.simplify(e) != 0 for e in origin - d * C):
        raise DerivationError(f"model '{model.name}': the frame of leg '{leg.leg.name}''s distal link is off its "
                              "middle axis; remove 'bodies: distal_link:'")
    com = d * w + sympy.Matrix(link.com)
    _, _, about_centre = about_origin(Body(link.link, link.mass, tuple(com), link.inertia))
    return DistalLink(leg.q, leg.C, leg.B, sympy.ImmutableMatrix(L.inv()), sympy.simplify(w.dot(v)), link.mass,
                      sympy.ImmutableMatrix(com),
                      sympy.ImmutableMatrix(about_centre))


def _swinging_rods(model: Model, bodies: ParallelBodies, legs: tuple[DistanceLeg, ...]) -> tuple[SwingingRod, ...]:
    """The legs' rods with ``rod: inertia:`` (see the module docstring); () without it."""
    if bodies.rod_inertia is None:
        return ()
    rods = []
    f = bodies.rod_platform_fraction
    for leg in legs:
        if leg.actuator == "rod":
            raise DerivationError(f"model '{model.name}': leg '{leg.leg.name}''s rod changes its length (its actuator "
                                  "is inside it), and a rod's own inertia is derived for rods of fixed length; "
                                  "remove 'bodies: rod: inertia:' (the rod's mass stays lumped at its ends)")
        rods.append(SwingingRod(leg.q, leg.C, leg.B, leg.L2,
                                bodies.rod_inertia - bodies.rod_mass * f * (1 - f) * leg.L2))
    return tuple(rods)


def _variables(leg: DistanceLeg, exclude: set[sympy.Symbol]) -> set[sympy.Symbol]:
    """The symbols of every joint variable of the leg but ``exclude``."""
    names = {v for j in leg.leg.joints for v in j.variables}
    return {sympy.Symbol(n, real=True) for n in names} - exclude


def split_inertia(model: Model, legs: tuple[DistanceLeg, ...], chains: tuple[LegChain, ...],
                  platform: Frame) -> Inertia:
    """The mass distribution of ``model`` (which must declare ``bodies:``) split as in the module docstring."""
    bodies = model.parallel.bodies if model.parallel is not None else None
    if bodies is None:
        raise DerivationError(f"model '{model.name}' declares no bodies, so it has no dynamics; add a 'bodies:' "
                              "section (platform, actuated_link, rod, rotor; see docs/model-format.md)")
    sides = [_actuator_side(model, bodies, leg, chain) for leg, chain in zip(legs, chains)]
    M_p, u_p = _platform(model, bodies, legs, platform)
    inertia = Inertia(tuple(s[0] for s in sides), sum((s[1] for s in sides), sympy.Integer(0)), M_p, u_p,
                      rods=_swinging_rods(model, bodies, legs))
    if bodies.distal_link is None:
        return inertia
    links = tuple(distal_link(model, bodies.distal_link, leg, chain) for leg, chain in zip(legs, chains))
    g = sympy.Matrix(model.gravity)
    potential = sum((-link.mass * g.dot(link.rotation * sympy.Matrix(link.com)) for link in links), sympy.Integer(0))
    return replace(inertia, distal_links=links, distal_potential=potential)

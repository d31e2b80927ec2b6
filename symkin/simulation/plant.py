"""The mechanism as a plant: joint-space rigid-body dynamics from the generated functions.

Seed eq. 8.34, tau = M(q) qdd + V(q, qd) + G(q) + F_f(qd), evaluated both ways through
the functions ``symkin derive`` emitted (``forward_dynamics`` gives qdd, ``inverse_dynamics``
gives tau), on whichever backend the model was loaded with (numpy, C, CasADi).  Nothing
here derives or imports sympy.

The TCP point of the haptic loop is the translational part of the model's task space
(``x``, ``y``, ``z`` components): its position comes from ``fk`` and its velocity Jacobian
from the rows of the task Jacobian ``jacobian``, so forces map to joint torques by
tau = J^T F (seed eq. 8.35) with zeros in the rotational rows.  A spherical platform's handle
only turns: the user holds its angles p = (roll, pitch, yaw), pd = J qd, and a generalized
force F conjugate to them (the moments about the partial rotation axes, N m) maps to the
joints by the same tau = J^T F.

The plant's joints are the mechanism's actuated joints (:class:`symkin.mechanism.actuated.Mechanism`, which the
plant asks instead of telling kinds of mechanism apart): a parallel mechanism's generated dynamics take the
platform pose p with q, which the mechanism supplies (p = fk(q) in closed form; legs without closed forms: their
dynamics reduced through the loop closure and the pose solved from the last one, :mod:`symkin.mechanism.closure`),
so the state stays (q, qd); a hybrid device's joints are z = (q, qw), the legs' then the wrist's, its TCP the
wrist's (``device_fk(p, qw)``) and its velocity Jacobian the translational rows of the actuator Jacobian
J_a = [J_c,p J, J_c,w] (``device_actuator_jacobian``), so tau = J_a^T [F; 0] drives every actuator.
"""

from __future__ import annotations

import numpy as np

from symkin import mechanism
from symkin.mechanism.actuated import Mechanism
from symkin.numerics.conditioning import inverse_condition_number
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import GeneratedModel

#: Functions a plant cannot do without, and how to get them (and fk where the joints carry a pose: p = fk(q)).
REQUIRED = ("forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy")


class Plant:
    """Joint-space dynamics of a serial model or a parallel mechanism with a closed-form fk
    (seed eq. 8.34) and the TCP point it drives.

    Args:
        model: a loaded model (``symkin.load(...)``), any backend, possibly ``bind()``-ed,
            with at least ``forward_dynamics``, ``inverse_dynamics`` and ``kinetic_energy``
            generated (``gravity_vector`` and ``potential_energy`` where the model has gravity,
            ``friction`` where it has friction; ``fk`` and ``jacobian`` for task-space work, and
            ``fk`` always for a parallel mechanism).

    Raises:
        GeneratedCodeError: a needed function was not generated.
    """

    def __init__(self, model: GeneratedModel):
        #: the model in its actuated joints: how the pose follows from them, the handle, the bound functions
        self.mechanism = Mechanism(model)
        functions = set(self.mechanism.functions)
        required = REQUIRED + (("fk",) if self.mechanism.has_pose else ())
        missing = [name for name in required if name not in functions]
        if missing:
            hint = (" (a closed-form fk: a DELTA, a pantograph, the Agile Eye; not a Stewart-Gough platform)"
                    if "fk" in missing else "")
            suggested = ",".join(dict.fromkeys(required + ("gravity_vector", "potential_energy", "fk", "jacobian")))
            raise GeneratedCodeError(f"{model.name}: simulation needs the generated {', '.join(missing)}{hint}; "
                                     f"derive the model with them, e.g. 'symkin derive MODEL --only {suggested}'")
        self.model = model
        self.name = model.name
        coordinates = self.mechanism.coordinates
        self.coordinates = tuple(c.name for c in coordinates)
        self.dof = len(self.coordinates)
        #: the model's declared position, velocity and effort limits per joint (inf, NaN where it declares none)
        self.joint_limits = np.array([c.bounds for c in coordinates], dtype=float).reshape(self.dof, 2)
        self.velocity_limits = np.array([np.nan if c.velocity_limit is None else c.velocity_limit
                                         for c in coordinates])
        self.effort_limits = np.array([np.nan if c.effort_limit is None else c.effort_limit for c in coordinates])
        self.revolute = np.array([c.revolute for c in coordinates], dtype=bool)
        #: which joints an actuator drives (False: passive, ``active: false``: no controller effort reaches it)
        self.actuated = np.array([c.active for c in coordinates], dtype=bool)
        self.passive = tuple(c.name for c in coordinates if not c.active)
        self.task_space = self.mechanism.task_space
        #: a spherical platform: its handle only turns, and the user holds its angles (roll, pitch, yaw)
        self.turning = self.mechanism.turns_only
        #: rows of the task Jacobian the user's hand holds (TCP translations; a turning handle's angles), their
        #: fk axes, and the units of a handle coordinate and of the force conjugate to it
        self.point_rows = np.array([i for i, c in enumerate(self.task_space)
                                    if self.turning or c in mechanism.POSITION_COMPONENTS], dtype=np.intp)
        self.point_axes = tuple(self.task_space[i] for i in self.point_rows)
        self.point_unit, self.force_unit = ("rad", "N m") if self.turning else ("m", "N")
        self._point_index = (self.point_rows if self.turning else
                             np.array([mechanism.POSITION_COMPONENTS.index(c) for c in self.point_axes], dtype=np.intp))
        task_functions = self.mechanism.handle_functions
        self._point_error = None if self.point_rows.size and task_functions <= functions else (
            f"{self.name}: task-space simulation needs {' and '.join(sorted(task_functions))} and a task space with "
            f"x, y or z, or a platform that only turns (it is [{', '.join(self.task_space)}])")
        bound = self.mechanism.function
        self._forward, self._inverse = bound("forward_dynamics"), bound("inverse_dynamics")
        self._mass, self._kinetic = bound("mass_matrix"), bound("kinetic_energy")
        task_jacobian = self.mechanism.task_jacobian_function
        self._jacobian = bound(task_jacobian) if task_jacobian in functions else None
        self._gravity = bound("gravity_vector") if "gravity_vector" in functions else None
        self._potential = bound("potential_energy") if "potential_energy" in functions else None
        self._friction = bound("friction") if "friction" in functions else None  # F_f(qd): no pose
        self._check_complete(functions)

    def pose(self, q: np.ndarray) -> np.ndarray:
        """The platform pose at the plant's joints q (:meth:`symkin.mechanism.actuated.Mechanism.pose`)."""
        return self.mechanism.pose(q)

    def middle_of_limits(self) -> np.ndarray:
        """(n,): the middle of each joint's limits, 0 for an unlimited joint."""
        finite = np.isfinite(self.joint_limits).all(axis=1)
        return np.where(finite, np.where(finite[:, None], self.joint_limits, 0.0).mean(axis=1), 0.0)

    def _check_complete(self, functions: set[str]) -> None:
        """Refuse a plant whose missing functions would silently read as zero.

        At a test state, ``inverse_dynamics(q, 0, 0)`` is G(q), and with ``coriolis_vector``
        ``inverse_dynamics(q, qd, 0) - inverse_dynamics(q, 0, 0) - V(q, qd)`` is F_f(qd).
        """
        q = self.mechanism.probe_configuration(self.middle_of_limits())
        qd = np.random.default_rng(8).uniform(-1.0, 1.0, self.dof)
        zero = np.zeros(self.dof)
        if not self.mechanism.assembles(q):
            raise GeneratedCodeError(f"{self.name}: the mechanism does not assemble at q = {q.tolist()}; declare a "
                                     "reachable parallel.home in the model file")
        static = np.asarray(self._inverse(q, zero, zero))
        if self._gravity is None and np.any(static != 0.0):
            raise GeneratedCodeError(f"{self.name}: the model has gravity but 'gravity_vector' was not generated; "
                                     "derive it with gravity_vector,potential_energy")
        if self._gravity is not None and self._potential is None:
            raise GeneratedCodeError(f"{self.name}: the energy balance needs 'potential_energy'; derive it too")
        if self._friction is None and "coriolis_vector" in functions:
            coriolis = self.mechanism.function("coriolis_vector")(q, qd)
            friction = self._inverse(q, qd, zero) - static - coriolis
            scale = np.max(np.abs(static)) + np.max(np.abs(coriolis)) + 1.0
            if np.max(np.abs(friction)) > 1e-9 * scale:
                raise GeneratedCodeError(f"{self.name}: the model has friction but 'friction' was not generated; "
                                         "derive it with friction")

    def drive(self, tau: np.ndarray) -> np.ndarray:
        """The efforts the actuators exert when a controller commands ``tau``: zero at a passive joint."""
        return np.where(self.actuated, tau, 0.0) if self.passive else tau

    def acceleration(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """qdd = M^-1 (tau - V - G - F_f) (generated ``forward_dynamics``)."""
        return self._forward(q, qd, tau)

    def torque(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """tau = M qdd + V + G + F_f (generated ``inverse_dynamics``, seed eq. 8.34)."""
        return self._inverse(q, qd, qdd)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q) (..., n, n) (generated ``mass_matrix``; the joint stops take their inertia from it)."""
        return self._mass(q)

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q) = du/dq, zero without gravity."""
        return self._gravity(q) if self._gravity is not None else np.zeros(np.shape(q))

    def friction(self, qd: np.ndarray) -> np.ndarray:
        """F_f(qd) (viscous + Coulomb), zero without friction."""
        return self._friction(qd) if self._friction is not None else np.zeros(np.shape(qd))

    def energy(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """k(q, qd) + u(q) (seed eq. 8.32)."""
        k = self._kinetic(q, qd)
        return k + self._potential(q) if self._potential is not None else k

    def point(self, q: np.ndarray) -> np.ndarray:
        """Position (..., d) of the TCP in the translational task axes (:attr:`point_axes`); a turning handle's
        angles (roll, pitch, yaw)."""
        self.require_point()
        return self.mechanism.handle_position(q, self._point_index)

    def point_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(..., d, n): TCP velocity = J_p qd, the translational rows of the task Jacobian (a turning handle's
        angle rates: all of J)."""
        self.require_point()
        return self.task_jacobian(q)[..., self.point_rows, :]

    def task_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(..., m, n): the task Jacobian J, pd = J qd (generated ``jacobian``; a hybrid device's
        ``device_actuator_jacobian``, the TCP's velocity and angular velocity)."""
        if self._jacobian is None:
            raise GeneratedCodeError(f"{self.name}: task-space simulation needs the generated "
                                     f"'{self.mechanism.task_jacobian_function}'")
        return self._jacobian(q)

    def dexterity(self, q: np.ndarray) -> np.ndarray:
        """1/kappa of the task Jacobian at q (...,): how well the TCP is driven from there.

        A hybrid device's rows and columns mix units (m/rad, rad/rad), so its figure is the worse of
        its parts': the platform's Jacobian J (the legs) and the wrist's angular Jacobian (the
        angular rows of J_a in the wrist's columns), each free of a characteristic length."""
        parts = self.mechanism.split_conditioning(q)
        if parts is None:
            return inverse_condition_number(self.task_jacobian(q))
        return np.minimum(*(inverse_condition_number(J) for J in parts))

    def require_point(self) -> None:
        """Raise GeneratedCodeError unless the plant has a TCP point (translational task axes, fk and a Jacobian)."""
        if self._point_error is not None:
            raise GeneratedCodeError(self._point_error)

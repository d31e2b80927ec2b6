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

A parallel mechanism (a DELTA, a pantograph, the Agile Eye) is a plant in its actuated coordinates q
too: its generated dynamics take the platform pose p with q (symkin.parallel.dynamics), which the plant
supplies from the closed-form forward kinematics, p = fk(q) (a spherical platform's orientation), so the
state stays (q, qd).  Legs without closed forms (the dual SCARA) take their dynamics reduced through the loop
closure and their pose solved from the last one (:mod:`symkin.mechanism.closure`).

A hybrid device (a DELTA carrying a wrist, symkin.parallel.hybrid) is a plant in its actuated
coordinates z = (q, qw): the legs' then the wrist's joints, as its generated dynamics return
them.  Its TCP is the wrist's (``device_fk(p, qw)``), its velocity Jacobian the translational
rows of the actuator Jacobian J_a = [J_c,p J, J_c,w] (``device_actuator_jacobian``), so
tau = J_a^T [F; 0] drives every actuator, the wrist's included.
"""

from __future__ import annotations

import numpy as np

from symkin import mechanism
from symkin.mechanism.closure import uses_closure
from symkin.numerics.conditioning import inverse_condition_number
from symkin.mechanism.device import DEVICE_TASK_SPACE
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import GeneratedModel
from symkin.simulation.integrate import SimulationError
from symkin.mechanism.closure import PLANT_FUNCTIONS, ClosureFunctions

#: Functions a plant cannot do without, and how to get them.
REQUIRED = ("forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy")
#: ... and a parallel mechanism's: its platform pose p = fk(q) (closed form).
REQUIRED_PARALLEL = REQUIRED + ("fk",)


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
        info = model.info
        self.parallel = info.is_parallel
        #: a hybrid device (a wrist on the platform): the plant's joints are the legs' then the wrist's
        self.hybrid = bool(info.wrist)
        self.legs = len(info.coordinates)
        self._last_pose: tuple[np.ndarray | None, np.ndarray] = (None, np.empty(0))
        #: legs without closed forms: the dynamics reduced through the closure, the pose solved from the last one
        self._closure = ClosureFunctions(model) if uses_closure(model) else None
        functions = set(model.functions) | set(PLANT_FUNCTIONS if self._closure is not None else ())
        required = REQUIRED_PARALLEL if self.parallel else REQUIRED
        missing = [name for name in required if name not in functions]
        if missing:
            hint = (" (a closed-form fk: a DELTA, a pantograph, the Agile Eye; not a Stewart-Gough platform)"
                    if self.parallel and "fk" in missing else "")
            suggested = ",".join(dict.fromkeys(required + ("gravity_vector", "potential_energy", "fk", "jacobian")))
            raise GeneratedCodeError(f"{model.name}: simulation needs the generated {', '.join(missing)}{hint}; "
                                     f"derive the model with them, e.g. 'symkin derive MODEL --only {suggested}'")
        self.model = model
        self.name = model.name
        coordinates = info.coordinates + info.wrist
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
        self.task_space = DEVICE_TASK_SPACE if self.hybrid else mechanism.task_space(model)
        #: a spherical platform: its handle only turns, and the user holds its angles (roll, pitch, yaw)
        self.turning = (self.parallel and not self.hybrid
                        and mechanism.kind_of(model) is mechanism.MechanismKind.PARALLEL_ORIENTATION)
        #: rows of the task Jacobian the user's hand holds (TCP translations; a turning handle's angles), their
        #: fk axes, and the units of a handle coordinate and of the force conjugate to it
        self.point_rows = np.array([i for i, c in enumerate(self.task_space)
                                    if self.turning or c in mechanism.POSITION_COMPONENTS], dtype=np.intp)
        self.point_axes = tuple(self.task_space[i] for i in self.point_rows)
        self.point_unit, self.force_unit = ("rad", "N m") if self.turning else ("m", "N")
        self._point_index = (self.point_rows if self.turning else
                             np.array([mechanism.POSITION_COMPONENTS.index(c) for c in self.point_axes], dtype=np.intp))
        task_functions = {"device_fk", "device_actuator_jacobian"} if self.hybrid else {"fk", "jacobian"}
        self._point_error = None if self.point_rows.size and task_functions <= functions else (
            f"{self.name}: task-space simulation needs {' and '.join(sorted(task_functions))} and a task space with "
            f"x, y or z, or a platform that only turns (it is [{', '.join(self.task_space)}])")
        self._forward, self._inverse = self._of_joints("forward_dynamics"), self._of_joints("inverse_dynamics")
        self._mass, self._kinetic = self._of_joints("mass_matrix"), self._of_joints("kinetic_energy")
        task_jacobian = "device_actuator_jacobian" if self.hybrid else "jacobian"
        self._jacobian = self._of_joints(task_jacobian) if task_jacobian in functions else None
        self._gravity = self._of_joints("gravity_vector") if "gravity_vector" in functions else None
        self._potential = self._of_joints("potential_energy") if "potential_energy" in functions else None
        self._friction = self._of_joints("friction") if "friction" in functions else None  # F_f(qd): no pose
        self._check_complete(functions)

    def _of_joints(self, name: str):
        """The generated function ``name`` as a function of the plant's joint vectors (q, then qd, qdd or tau as
        the function takes them): a parallel mechanism's takes the platform pose p = fk(q) after q, a hybrid
        device's the wrist's part of each vector after the legs' (``qw`` after ``q``...), as its manifest names
        the inputs."""
        if self._closure is not None:
            return self._closure.function(name)
        return mechanism.of_device_joints(self.model, name, self.pose)

    @property
    def inverse_in_closed_form(self) -> bool:
        """Whether the plant's joints follow from task targets in closed form (:meth:`joints_at`: a platform's
        generated ik) rather than by a numerical solve along a path (an open chain's)."""
        return self.parallel

    def joints_at(self, targets: np.ndarray, q_start: np.ndarray) -> np.ndarray:
        """The plant's joints (N, n) at task targets (N, task dof) by the generated ik (a hybrid device's wrist held
        at ``q_start``'s), NaN rows where ik has no solution.

        Raises:
            SimulationError: ik was not generated.
        """
        if "ik" not in self.model.functions:
            raise SimulationError(f"{self.name}: a task-space circle of a parallel mechanism needs the generated 'ik'")
        legs = np.asarray(self.model.ik(targets).joints, dtype=float)
        return np.concatenate([legs, np.tile(np.asarray(q_start, dtype=float)[self.legs:], (len(targets), 1))],
                              axis=-1)

    def pose(self, q: np.ndarray) -> np.ndarray:
        """A parallel mechanism's platform pose p = fk(q) (..., task dof) of the legs' joints q (a hybrid
        device's: the first :attr:`legs` of its joints); NaN where it does not assemble.

        The last q and its pose are kept: one step of the loop asks for the pose of one q up to five times
        (the TCP point and Jacobian, gravity compensation, the acceleration)."""
        q = np.asarray(q, dtype=float)[..., :self.legs]
        if self._closure is not None:
            return self._closure.pose(q)
        last_q, last_p = self._last_pose
        if last_q is not None and q.shape == last_q.shape and np.array_equal(q, last_q):
            return last_p
        p = np.asarray(self.model.fk(q)[0])  # the platform's coordinates: a position, or a spherical one's angles
        self._last_pose = (q.copy(), p)
        return p

    def _test_configuration(self) -> np.ndarray:
        """A configuration to probe the generated functions at: random for a serial chain, the
        declared home pose's (q = ik(home)) or q = 0 for a parallel mechanism, which must assemble
        (a hybrid device's wrist in the middle of its limits)."""
        if not self.parallel:
            return np.random.default_rng(7).uniform(-1.0, 1.0, self.dof)
        if self._closure is not None:
            return self._closure.home
        home = self.model.info.home
        legs = (np.asarray(self.model.ik(np.asarray(home, dtype=float)).joints, dtype=float)
                if home is not None and "ik" in self.model.functions else np.zeros(self.legs))
        return np.concatenate([legs, self.middle_of_limits()[self.legs:]])

    @property
    def home_configuration(self) -> np.ndarray | None:
        """(n,): a serial device's declared rest configuration (``serial.home``), None where it declares none; legs
        without closed forms: the actuators of their home assembly (at the declared home pose ``parallel.home``)."""
        if self._closure is not None:
            return self._closure.home
        declared = self.model.info.home_configuration
        return None if declared is None or self.parallel else np.array(declared, dtype=float)

    def middle_of_limits(self) -> np.ndarray:
        """(n,): the middle of each joint's limits, 0 for an unlimited joint."""
        finite = np.isfinite(self.joint_limits).all(axis=1)
        return np.where(finite, np.where(finite[:, None], self.joint_limits, 0.0).mean(axis=1), 0.0)

    def _check_complete(self, functions: set[str]) -> None:
        """Refuse a plant whose missing functions would silently read as zero.

        At a test state, ``inverse_dynamics(q, 0, 0)`` is G(q), and with ``coriolis_vector``
        ``inverse_dynamics(q, qd, 0) - inverse_dynamics(q, 0, 0) - V(q, qd)`` is F_f(qd).
        """
        q, qd = self._test_configuration(), np.random.default_rng(8).uniform(-1.0, 1.0, self.dof)
        zero = np.zeros(self.dof)
        if self.parallel and not np.all(np.isfinite(self.pose(q))):
            raise GeneratedCodeError(f"{self.name}: the mechanism does not assemble at q = {q.tolist()}; declare a "
                                     "reachable parallel.home in the model file")
        static = np.asarray(self._inverse(q, zero, zero))
        if self._gravity is None and np.any(static != 0.0):
            raise GeneratedCodeError(f"{self.name}: the model has gravity but 'gravity_vector' was not generated; "
                                     "derive it with gravity_vector,potential_energy")
        if self._gravity is not None and self._potential is None:
            raise GeneratedCodeError(f"{self.name}: the energy balance needs 'potential_energy'; derive it too")
        if self._friction is None and "coriolis_vector" in functions:
            coriolis = self._of_joints("coriolis_vector")(q, qd)
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
        if self.hybrid:
            return self.model.device_fk(self.pose(q), q[..., self.legs:])[..., self._point_index, 3]
        if self.parallel:
            return self.pose(q)[..., self._point_index]
        return self.model.fk(q)[..., self._point_index, 3]

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
                                     f"'{'device_actuator_jacobian' if self.hybrid else 'jacobian'}'")
        return self._jacobian(q)

    def dexterity(self, q: np.ndarray) -> np.ndarray:
        """1/kappa of the task Jacobian at q (...,): how well the TCP is driven from there.

        A hybrid device's rows and columns mix units (m/rad, rad/rad), so its figure is the worse of
        its parts': the platform's Jacobian J (the legs) and the wrist's angular Jacobian (the
        angular rows of J_a in the wrist's columns), each free of a characteristic length."""
        if not self.hybrid:
            return inverse_condition_number(self.task_jacobian(q))
        if "jacobian" not in self.model.functions:
            raise GeneratedCodeError(f"{self.name}: the platform's dexterity needs the generated 'jacobian'")
        legs = np.asarray(q, dtype=float)[..., :self.legs]
        platform = inverse_condition_number(self.model.jacobian(legs, self.pose(legs)))
        angular = [i for i, c in enumerate(self.task_space) if c not in mechanism.POSITION_COMPONENTS]
        wrist = inverse_condition_number(self.task_jacobian(q)[..., angular, self.legs:])
        return np.minimum(platform, wrist)

    def require_point(self) -> None:
        """Raise GeneratedCodeError unless the plant has a TCP point (translational task axes, fk and a Jacobian)."""
        if self._point_error is not None:
            raise GeneratedCodeError(self._point_error)

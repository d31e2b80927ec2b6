"""A loaded model as one mechanism in its actuated joints (issue 62): the object the simulation, the identification
and the excitation ask instead of telling kinds of mechanism apart.

Its joints z are the actuated joints of the model: an open chain's joints; a parallel mechanism's actuators q,
whose passive joints s and platform pose p follow from them; a hybrid device's z = (q, qw), the legs' then the
wrist's (:mod:`symkin.parallel.hybrid`).  :class:`Mechanism` answers the two questions every analysis asks:

* **assembly** - the platform pose at z (:meth:`Mechanism.pose`): the closed-form fk p = fk(q) where the model
  has one (kept for the last q: one step of a loop asks for it up to five times), else the continuation of the
  generated closure from the last assembly (:class:`symkin.mechanism.closure.ClosureFunctions`); an open chain
  has none.  :meth:`Mechanism.joints_at` inverts it in closed form where the generated ik exists;
* **handle** - what the task space measures (:attr:`Mechanism.task_space`; a hybrid device's handle is its wrist's
  TCP, :data:`symkin.mechanism.device.DEVICE_TASK_SPACE`), whether it only turns (a spherical platform), and its
  position (:meth:`Mechanism.handle_position`);

and binds each generated function once to the joint vectors (:meth:`Mechanism.function`: the pose added where a
function takes it, a hybrid device's vectors split into the legs' and the wrist's parts, legs without closed forms
through their closure).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin import mechanism
from symkin.errors import GeneratedCodeError
from symkin.mechanism.closure import REGRESSORS, ClosureFunctions, uses_closure
from symkin.mechanism.device import DEVICE_TASK_SPACE
from symkin.runtime.info import GeneratedModel
from symkin.runtime.parallel import solve_fk


class Mechanism:
    """A loaded model in its actuated joints (the module docstring).

    Attributes:
        model: the loaded model.
        functions: the names of the functions :meth:`function` gives (the generated ones; for legs without closed
            forms also the dynamics reduced through their closure).
        task_space: the handle's task coordinates.
        turns_only: the handle only turns (a spherical platform's roll, pitch, yaw).
        coordinates: the manifest's records of the joints z, in their order.
        dof: the number of actuated joints z.

    Raises:
        GeneratedCodeError: legs without closed forms lack their generated closure dynamics
            (:class:`symkin.mechanism.closure.ClosureFunctions`).
    """

    def __init__(self, model: GeneratedModel):
        info = model.info
        self.model = model
        self._closes_loops = info.is_parallel
        self._wrist = bool(info.wrist)
        self._legs = len(info.coordinates)
        self.coordinates = info.coordinates + info.wrist
        self.dof = len(self.coordinates)
        self._closure = ClosureFunctions(model) if uses_closure(model) else None
        self.functions = frozenset(model.functions) | frozenset(self._closure.names if self._closure is not None
                                                                else ())
        #: the manifest's view of the mechanism in z: its joints' records as its coordinates (a hybrid device's
        #: wrist after the legs) and, for legs without closed forms, the records of the closure's regressors under
        #: the names of the actuators' (they name the same parameters)
        records = dict(info.functions)
        if self._closure is not None:
            records |= {name: records[closure] for name, closure in REGRESSORS.items() if closure in records}
        self.info = dataclasses.replace(info, coordinates=self.coordinates, wrist=(), functions=records)
        self._last_pose: tuple[np.ndarray | None, np.ndarray] = (None, np.empty(0))
        self._bound: dict[str, Callable[..., Any]] = {}
        self.task_space = DEVICE_TASK_SPACE if self._wrist else mechanism.task_space(model)
        self.turns_only = not self._wrist and mechanism.turns_only(model)

    @property
    def has_pose(self) -> bool:
        """Whether the actuated joints carry a platform pose p (a mechanism that closes loops)."""
        return self._closes_loops

    @property
    def task_jacobian_function(self) -> str:
        """The generated function of the handle's Jacobian in the actuated joints: a hybrid device's actuator
        Jacobian J_a = [J_c,p J, J_c,w] (``device_actuator_jacobian``), else ``jacobian``."""
        return "device_actuator_jacobian" if self._wrist else "jacobian"

    @property
    def handle_functions(self) -> frozenset[str]:
        """The generated functions the handle's position and Jacobian need."""
        return frozenset({"device_fk", "device_actuator_jacobian"} if self._wrist else {"fk", "jacobian"})

    def function(self, name: str) -> Callable[..., Any]:
        """The generated function ``name`` as a function of the actuated joint vectors (z, then zd, zdd or tau as the
        function takes them): the platform pose p = pose(z) added after q where it takes it, a hybrid device's
        vectors split into the legs' and the wrist's parts (``qw`` after ``q``...) as its manifest names the inputs,
        legs without closed forms' dynamics reduced through their closure."""
        if name not in self._bound:  # bound once: the loops and the dexterity ask again at every step
            self._bound[name] = (self._closure.function(name) if self._closure is not None else
                                 mechanism.of_device_joints(self.model, name, self.pose))
        return self._bound[name]

    def pose(self, z: np.ndarray) -> np.ndarray:
        """The platform pose p (..., task dof) of the legs' joints q (the first joints of z); NaN where it does not
        assemble: fk(q) in closed form; a platform without one (the Stewart-Gough platform) by Newton's method on
        the generated leg equations (:meth:`_solved_poses`); legs without closed forms through their closure.  The
        last q and its pose are kept."""
        q = np.asarray(z, dtype=float)[..., :self._legs]
        if self._closure is not None:
            return self._closure.pose(q)
        last_q, last_p = self._last_pose
        if last_q is not None and q.shape == last_q.shape and np.array_equal(q, last_q):
            return last_p
        with np.errstate(invalid="ignore"):  # NaN where the legs do not assemble, as documented
            if "fk" in self.model.functions:
                p = np.asarray(self.model.fk(q)[0])  # a position, or a spherical platform's angles
            else:
                p = self._solved_poses(q)
        self._last_pose = (q.copy(), p)
        return p

    def _solved_poses(self, q: np.ndarray) -> np.ndarray:
        """p with f(q, p) = 0 for every row of q (N, n) by Newton from the home pose
        (:func:`symkin.runtime.parallel.solve_fk`); the rows that do not converge from there start again from the
        previous row's pose (a run is continuous), pass after pass while some do (NaN where none does)."""
        p = np.array(solve_fk(self.model, q).solution)
        if p.ndim < 2:
            return p
        while True:
            failed = np.flatnonzero(~np.all(np.isfinite(p), axis=-1))
            failed = failed[(failed > 0) & np.all(np.isfinite(p[failed - 1]), axis=-1)]
            if not failed.size:
                return p
            p[failed] = solve_fk(self.model, q[failed], p[failed - 1]).solution
            if not np.any(np.all(np.isfinite(p[failed]), axis=-1)):
                return p

    def assembly(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, p) at z: the passive joints a closure solve finds (legs without closed forms; (..., 0) for a mechanism
        whose closed forms or leg equations give the pose alone) and the platform pose (:meth:`pose`)."""
        if self._closure is not None:
            return self._closure.assembled(np.asarray(z, dtype=float)[..., :self._legs])
        p = self.pose(z)
        return np.zeros(p.shape[:-1] + (0,)), p

    @property
    def unassembled(self) -> str:
        """Why a configuration has no pose, in words, as :meth:`pose` finds it."""
        if self._closure is not None:
            return "the closure has no solution continued from the previous sample"
        return "fk has no solution" if "fk" in self.model.functions else \
            "Newton's method on the leg equations does not converge"

    def assembles(self, z: np.ndarray) -> bool:
        """Whether the mechanism assembles at z (always for an open chain)."""
        return not self._closes_loops or bool(np.all(np.isfinite(self.pose(z))))

    @property
    def inverse_in_closed_form(self) -> bool:
        """Whether the joints follow from task targets in closed form (:meth:`joints_at`: a platform's generated
        ik) rather than by a numerical solve along a path (an open chain's)."""
        return self._closes_loops

    def joints_at(self, targets: np.ndarray, z_start: np.ndarray) -> np.ndarray:
        """The actuated joints (N, n) at task targets (N, task dof) by the generated ik (a hybrid device's wrist held
        at ``z_start``'s), NaN rows where ik has no solution.

        Raises:
            GeneratedCodeError: ik was not generated.
        """
        if "ik" not in self.model.functions:
            raise GeneratedCodeError(f"{self.model.name}: following task targets in closed form needs the generated "
                                     "'ik'")
        legs = np.asarray(self.model.ik(targets).joints, dtype=float)
        return np.concatenate([legs, np.tile(np.asarray(z_start, dtype=float)[self._legs:], (len(targets), 1))],
                              axis=-1)

    def handle_position(self, z: np.ndarray, index: np.ndarray) -> np.ndarray:
        """The handle's coordinates ``index`` (..., d) at z: the TCP's position components (of a 4 x 4 fk; a hybrid
        device's wrist TCP, ``device_fk``) or, for a mechanism with a pose, of the pose (a turning handle's angles)."""
        if self._wrist:
            return self.model.device_fk(self.pose(z), np.asarray(z)[..., self._legs:])[..., index, 3]
        if self._closes_loops:
            return self.pose(z)[..., index]
        return self.model.fk(z)[..., index, 3]

    def split_conditioning(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The Jacobians whose 1/kappa rate a hybrid device's dexterity, each free of a characteristic length: the
        platform's J (the legs, at the pose) and the wrist's angular Jacobian (the angular rows of J_a in the wrist's
        columns); None for a mechanism whose task Jacobian is rated whole.

        Raises:
            GeneratedCodeError: the platform's ``jacobian`` or the actuator Jacobian was not generated.
        """
        if not self._wrist:
            return None
        for name in ("jacobian", self.task_jacobian_function):
            if name not in self.model.functions:
                raise GeneratedCodeError(f"{self.model.name}: the dexterity needs the generated '{name}'")
        legs = np.asarray(z, dtype=float)[..., :self._legs]
        platform = self.model.jacobian(legs, self.pose(legs))
        angular = [i for i, c in enumerate(self.task_space) if c not in mechanism.POSITION_COMPONENTS]
        wrist = self.function(self.task_jacobian_function)(z)[..., angular, self._legs:]
        return platform, wrist

    def probe_configuration(self, middle: np.ndarray) -> np.ndarray:
        """A configuration to probe the generated functions at: random for an open chain; for a mechanism that
        closes loops the declared home pose's (q = ik(home)), its home assembly's or q = 0, which must assemble
        (a hybrid device's wrist at ``middle``'s, the middle of its limits)."""
        if not self._closes_loops:
            return np.random.default_rng(7).uniform(-1.0, 1.0, self.dof)
        if self._closure is not None:
            return self._closure.home
        home = self.model.info.home
        legs = (np.asarray(self.model.ik(np.asarray(home, dtype=float)).joints, dtype=float)
                if home is not None and "ik" in self.model.functions else np.zeros(self._legs))
        return np.concatenate([legs, np.asarray(middle, dtype=float)[self._legs:]])

    @property
    def home_configuration(self) -> np.ndarray | None:
        """(n,): an open chain's declared rest configuration (``serial.home``), None where it declares none; legs
        without closed forms: the actuators of their home assembly (at the declared home pose ``parallel.home``)."""
        if self._closure is not None:
            return self._closure.home
        declared = self.model.info.home_configuration
        return None if declared is None or self._closes_loops else np.array(declared, dtype=float)

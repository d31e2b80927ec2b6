"""The plant's functions of the joints for legs without closed forms (issue 31): the generated ``closure_dynamics``
reduced at each state (:mod:`symkin.runtime.closure_dynamics`), the passive joints and the platform pose solved from
the actuated joints by Gauss-Newton on the generated closure.

A :class:`symkin.simulation.plant.Plant` asks for functions of the actuated joints q only (a parallel mechanism
with a closed-form fk takes p = fk(q)).  Legs without closed forms have no fk: the assembly (s, p) at q is solved
from the last one (:func:`symkin.runtime.parallel.solve_closure`, unknowns p and s), which a simulation's steps keep
near, so the mechanism stays in the assembly mode it starts in (the home assembly,
:func:`symkin.analysis.closure_workspace.assemble_at_home`).  A batch of configurations (a recorded trajectory) is
solved row by row, each from the previous row's assembly or the home assembly, whichever is nearer, continued
along the straight line of actuator positions in steps of at most MAX_STEP (a trajectory's first row, read after
the run ended far from it, is not solved from the run's end).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from symkin.analysis.closure_workspace import MAX_STEP, assemble_at_home
from symkin.errors import GeneratedCodeError
from symkin.runtime.closure_dynamics import ActuatedDynamics, actuated_dynamics
from symkin.runtime.info import GeneratedModel
from symkin.runtime.parallel import solve_closure


#: The generated functions a plant asks for, which :class:`ClosureFunctions` provides for legs without closed forms.
PLANT_FUNCTIONS = ("forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy", "gravity_vector",
                   "potential_energy", "jacobian", "fk")
#: The generated closure functions the plant needs.
NEEDED = ("closure", "closure_jacobians", "closure_dynamics")


class ClosureAssembly:
    """(s, p) of a generated model of legs without closed forms at its actuated joints q, continued from its home
    assembly (the module docstring); ``assembly(q)``.

    Raises:
        GeneratedCodeError: its legs do not close at the home pose.
    """

    def __init__(self, model: GeneratedModel):
        self.model = model
        try:
            q, s = assemble_at_home(model)
        except ValueError as error:
            raise GeneratedCodeError(str(error)) from None
        self.home = q
        self._home = (q, s, np.asarray(model.info.home, dtype=float))
        self._last = self._home

    def _solve(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(q, s, p) at q, continued from the nearer (in the actuators) of the last assembly and the home assembly
        along the straight line of actuator positions, in steps of at most MAX_STEP (one step within a simulation);
        None where the legs stop closing on the way."""
        start = min((self._last, self._home), key=lambda known: float(np.max(np.abs(q - known[0]))))
        if np.array_equal(q, start[0]):
            return start
        steps = max(1, int(np.ceil(np.max(np.abs(q - start[0])) / MAX_STEP)))
        s, p = start[1], start[2]
        for fraction in np.linspace(0.0, 1.0, steps + 1)[1:]:
            report = solve_closure(self.model, start[0] + fraction * (q - start[0]), s, p, unknowns=("p", "s"),
                                   max_step=MAX_STEP)
            solution = report.solution
            assert isinstance(solution, dict), "solve_closure names its vectors"
            if not report.all_converged:
                return None
            s, p = solution["s"], solution["p"]
        return q.copy(), s, p

    def __call__(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, p) (..., ns), (..., m) at the actuated joints q, each row continued from the last assembly or the home
        assembly, whichever is nearer (row by row for a batch: a recorded trajectory from its start); NaN where the
        legs do not close."""
        q = np.asarray(q, dtype=float)
        rows = q.reshape(-1, q.shape[-1])
        s, p = [], []
        for row in rows:
            solved = self._solve(row)
            if solved is None:
                s.append(np.full_like(self._home[1], np.nan))
                p.append(np.full_like(self._home[2], np.nan))
            else:
                self._last = solved
                s.append(solved[1])
                p.append(solved[2])
        return np.reshape(s, q.shape[:-1] + (-1,)), np.reshape(p, q.shape[:-1] + (-1,))


class ClosureFunctions:
    """The dynamics of legs without closed forms as functions of the actuated joints (see the module docstring).

    Raises:
        GeneratedCodeError: the model lacks ``closure_dynamics`` (no bodies declared), or ``friction`` where its
            joints declare friction, or its legs do not close at the home pose.
    """

    def __init__(self, model: GeneratedModel):
        missing = [name for name in NEEDED if name not in model.functions]
        if "friction" not in model.functions and any(c.viscous is not None for c in model.info.coordinates):
            missing.append("friction")  # it would silently read as zero
        if missing:
            outputs = ",".join(NEEDED + (("friction",) if "friction" in missing else ()))
            raise GeneratedCodeError(f"{model.name}: its legs have no closed forms; simulating them needs the generated "
                                     f"{', '.join(missing)} (declare bodies: links: and platform:, and derive with "
                                     f"--only {outputs})")
        self.model = model
        self.assembly = ClosureAssembly(model)
        self.home = self.assembly.home
        self._last_dynamics: tuple[np.ndarray, np.ndarray, ActuatedDynamics] | None = None

    def pose(self, q: np.ndarray) -> np.ndarray:
        """The platform pose p (..., m) at q."""
        return self.assembly(q)[1]

    def dynamics(self, q: np.ndarray, qd: np.ndarray) -> ActuatedDynamics:
        """M, the bias efforts, W and the energies at (q, qd); the last state's are kept (a step of the loop asks
        for its acceleration, TCP Jacobian and gravity at one state)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if self._last_dynamics is not None:
            last_q, last_qd, terms = self._last_dynamics
            if q.shape == last_q.shape and np.array_equal(q, last_q) and np.array_equal(qd, last_qd):
                return terms
        s, p = self.assembly(q)
        terms = actuated_dynamics(self.model, q, s, p, qd)
        self._last_dynamics = (q.copy(), qd.copy(), terms)
        return terms

    def _at(self, q: np.ndarray, *, at_rest: bool) -> ActuatedDynamics:
        """The terms at q: the last state's when it was at q (M, W and u do not depend on qd) and, ``at_rest``, not
        moving (the bias efforts at qd = 0 are the gravity efforts); else evaluated at qd = 0."""
        last = self._last_dynamics
        if (last is not None and np.shape(q) == last[0].shape and np.array_equal(q, last[0])
                and not (at_rest and np.any(last[1]))):
            return last[2]
        return self.dynamics(q, np.zeros(np.shape(q)))

    def function(self, name: str) -> Callable[..., np.ndarray]:
        """The plant's function ``name`` (one of :data:`PLANT_FUNCTIONS` but fk: a generated function's name and
        signature, in the joints only)."""
        return getattr(self, f"_{name}")

    def _forward_dynamics(self, q, qd, tau):
        return self.dynamics(q, qd).accelerations(tau)

    def _inverse_dynamics(self, q, qd, qdd):
        return self.dynamics(q, qd).efforts(qdd)

    def _mass_matrix(self, q):
        return self._at(q, at_rest=False).M

    def _gravity_vector(self, q):
        return self._at(q, at_rest=True).bias

    def _friction(self, qd):
        return self.model.friction(qd)

    def _kinetic_energy(self, q, qd):
        return self.dynamics(q, qd).kinetic

    def _potential_energy(self, q):
        return self._at(q, at_rest=False).potential

    def _jacobian(self, q):
        """J = dp/dq: the p rows of W."""
        W = self._at(q, at_rest=False).W
        return W[..., W.shape[-2] - len(self.model.info.task_space):, :]

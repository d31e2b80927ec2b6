"""The closure as the general method of assembly (issue 62): a parallel mechanism of any leg topology assembled from
its generated loop closure phi(q, s, p) = 0 alone, as every analysis, the simulation, the identification and the
excitation design ask it.

* **Home assembly** (:func:`solve_home_assembly`): (q, s) closing the legs at the home pose ``parallel.home``
  within the declared limits of the actuators and passive joints, by Gauss-Newton
  (:func:`symkin.runtime.parallel.solve_closure`) from the declared ``parallel.home_assembly`` or from fixed starts;
  the assembly mode every other solve stays in.
* **Continuation along the actuators** (:class:`ClosureAssembly`): (s, p) at actuated joints q, solved from the
  last assembly or the home assembly, whichever is nearer, along the straight line of actuator positions in steps
  of at most :data:`MAX_STEP` (unknowns p and s); a batch (a recorded trajectory) row by row, each from the
  previous row's (a trajectory's first row, read after the run ended far from it, is not solved from the run's
  end); NaN where the legs stop closing.  A model loaded with the C backend takes each step by its generated
  assembly (:class:`symkin.runtime.assembly.GeneratedAssembly`, microseconds), and the run-time Gauss-Newton
  where that one refuses or flags a jump of assembly mode.
* **Dynamics of the actuated joints** (:class:`ClosureFunctions`): the generated ``closure_dynamics`` reduced at
  each state (:mod:`symkin.runtime.closure_dynamics`) and the regressors over all the closure's variables taken to
  the actuators (Y = W^T Y_z, the identification's) as functions of q alone - the functions a
  :class:`symkin.simulation.plant.Plant` asks of a mechanism without closed forms (one with a closed-form fk takes
  p = fk(q)).

The workspace of such legs (a flood of the closure over a grid of poses) builds on these:
:mod:`symkin.analysis.continued_workspace`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from symkin.errors import GeneratedCodeError
from symkin.runtime.closure_dynamics import (ActuatedDynamics, actuated_dynamics, closure_energy_regressor,
                                             closure_regressor)
from symkin.runtime.info import GeneratedModel
from symkin import mechanism
from symkin.mechanism.passive import AssemblyLimits, declared_limits
from symkin.runtime.assembly import GeneratedAssembly
from symkin.runtime.loader import LoadedModel
from symkin.runtime.parallel import solve_closure


#: Random starts (besides q = s = 0 and the middle of the limits) of the home assembly, uniform in [-pi/2, pi/2] per variable.
HOME_STARTS = 16
#: Gauss-Newton from a neighbouring cell: iterations, the longest step (rad or m) and the step that converges.
SOLVE_ITERATIONS, MAX_STEP, SOLVE_TOLERANCE = 30, 0.2, 1e-12
#: The legs close where every closure row is below this times the pose's scale (m): a converged solve leaves
#: rounding, ~1e-15; Gauss-Newton can also stop at a least-squares minimum of the closure, which misses by a link.
CLOSED = 1e-9


def uses_closure(model: GeneratedModel) -> bool:
    """Whether a parallel model is analysed through its loop closure: it has the generated ``closure`` and
    ``closure_jacobians`` but no closed-form ``ik`` (legs without the distance form)."""
    return mechanism.is_parallel(model) and mechanism.closure_alone(model.functions)


def closure_sizes(model: GeneratedModel) -> tuple[int, int]:
    """(n, ns): the actuated and passive joint counts, from the generated closure's inputs."""
    inputs = model.info.functions["closure"].inputs
    return int(inputs[0].shape[0]), int(inputs[1].shape[0])


@dataclass(frozen=True)
class HomeAssembly:
    """The assembly the analyses continue the closure from: (q, s) closing the legs at the home pose, and the
    start of the Gauss-Newton solve that reached it (:func:`solve_home_assembly`)."""

    q: np.ndarray
    s: np.ndarray
    start: str

    def describe(self, model: GeneratedModel) -> str:
        """'home assembly (... from q = s = 0): theta1 = 12.3 deg, ...; passive: knee1 = -60 deg, ...', in deg
        (to 0.01) or mm (to 0.001) as the closure's inputs are rad or m."""
        inputs = model.info.functions["closure"].inputs

        def values(spec, vector: np.ndarray) -> str:
            return ", ".join(f"{name} = {round(np.degrees(v), 2) + 0.0:g} deg" if unit == "rad"   # + 0.0: no -0
                             else f"{name} = {round(1000 * v, 3) + 0.0:g} mm"
                             for name, unit, v in zip(spec.elements, spec.units, vector))

        return (f"home assembly (Gauss-Newton at the home pose from {self.start}): {values(inputs[0], self.q)}; "
                f"passive: {values(inputs[1], self.s)}")


def within_declared_limits(model: GeneratedModel, q: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Boolean (K,): the actuators q (K, n) within their declared limits (a coordinate without limits is free) and
    the passive joints s (K, ns) within theirs (``passive_limits``); angles are taken modulo 2 pi."""
    bounds = np.array(model.joint_limits, dtype=np.float64).reshape(-1, 2)
    return AssemblyLimits(bounds, mechanism.revolute_mask(model), declared_limits(model)).hold(q, s)


def solve_home_assembly(model: GeneratedModel) -> HomeAssembly:
    """(q, s) closing the legs at the home pose ``parallel.home`` within the declared joint limits
    (:func:`within_declared_limits`): Gauss-Newton from the model's declared ``parallel.home_assembly`` (its named
    variables, 0 for the others) where it has one; else the first of q = s = 0, the middle of the actuators' limits
    (s = 0) and :data:`HOME_STARTS` fixed random starts that closes them there (deterministic).  An assembly outside
    the limits is another the device cannot take (an S-P-S strut of negative length: the rod turned around).

    Raises:
        ValueError: no start closes the legs within the limits (the home pose is out of reach, or the declared start
            leads nowhere or outside the limits).
    """
    home = mechanism.home_pose(model)
    n, ns = closure_sizes(model)
    declared = model.info.home_assembly
    if declared is not None:
        inputs = model.info.functions["closure"].inputs
        names = list(inputs[0].elements) + list(inputs[1].elements)
        starts = np.zeros((1, n + ns))
        for name, value in declared.items():
            starts[0, names.index(name)] = value
        described = ["the declared parallel.home_assembly"]
    else:
        bounds = np.array(model.joint_limits, dtype=np.float64).reshape(-1, 2)
        finite = np.all(np.isfinite(bounds), axis=1, keepdims=True)  # an actuator without limits starts at 0
        middle = np.concatenate([np.where(finite, bounds, 0.0).mean(axis=1), np.zeros(ns)])
        starts = np.vstack([np.zeros(n + ns), middle,
                            np.random.default_rng(0).uniform(-np.pi / 2, np.pi / 2, (HOME_STARTS, n + ns))])
        described = ["q = s = 0", "the middle of the actuators' limits, s = 0"] + [
            f"random start {k} of {HOME_STARTS} (q = s = 0 did not close the legs within the limits)"
            for k in range(1, HOME_STARTS + 1)]
    report = solve_closure(model, starts[:, :n], starts[:, n:], home, unknowns=("q", "s"), max_step=MAX_STEP,
                           max_iterations=100)
    solution = report.solution
    assert isinstance(solution, dict), "solve_closure names its vectors"
    closing = closes(report, home)
    accepted = np.flatnonzero(closing & within_declared_limits(model, solution["q"], solution["s"]))
    if not len(accepted):
        where = ("from the declared parallel.home_assembly: change its values" if declared is not None
                 else f"from {len(starts)} starts: declare a home pose inside the workspace, or parallel.home_assembly")
        outside = " (they close only outside the declared joint limits)" if closing.any() else ""
        raise ValueError(f"{model.name}: the legs do not close at the home pose {home.tolist()} (parallel.home)"
                         f"{outside} {where}")
    return HomeAssembly(solution["q"][accepted[0]], solution["s"][accepted[0]], described[accepted[0]])


def assemble_at_home(model: GeneratedModel) -> tuple[np.ndarray, np.ndarray]:
    """(q, s) of the home assembly (:func:`solve_home_assembly`)."""
    found = solve_home_assembly(model)
    return found.q, found.s


def closes(report, p: np.ndarray) -> np.ndarray:
    """Boolean (K,): the solve converged to a pose that closes the legs (not a least-squares minimum)."""
    scale = np.maximum(np.max(np.abs(p), axis=-1), 1.0)
    return report.converged & (report.residual <= CLOSED * scale)


#: The generated functions a plant asks for, which :class:`ClosureFunctions` provides for legs without closed forms.
PLANT_FUNCTIONS = ("forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy", "gravity_vector",
                   "potential_energy", "jacobian", "fk")
#: The generated closure functions the plant needs.
NEEDED = ("closure", "closure_jacobians", "closure_dynamics")
#: The regressors of the actuators :class:`ClosureFunctions` gives, each from the generated regressor over all the
#: closure's variables (:func:`symkin.runtime.closure_dynamics.closure_regressor`: Y = W^T Y_z).
REGRESSORS = {"regressor": "closure_regressor", "base_regressor": "closure_base_regressor",
              "energy_regressor": "closure_energy_regressor"}
#: The functions whose values hold the friction efforts (the generated ``friction`` must not be missing there).
WITH_FRICTION = ("forward_dynamics", "inverse_dynamics")


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
        #: the generated assembly of a model loaded with the C backend, else None (the run-time solver only)
        self.generated = generated_assembly(model)

    def _step(self, q: np.ndarray, s: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """(s, p) at q from the neighbouring assembly (s, p): the generated assembly's where it converged in the
        start's mode, else the run-time Gauss-Newton's; None where the legs do not close."""
        if self.generated is not None:
            s1, p1 = s.copy(), p.copy()
            if self.generated.assemble(q, s1, p1)[0] > 0:
                return s1, p1
        report = solve_closure(self.model, q, s, p, unknowns=("p", "s"), max_step=MAX_STEP)
        solution = report.solution
        assert isinstance(solution, dict), "solve_closure names its vectors"
        return (solution["s"], solution["p"]) if report.all_converged else None

    def _solve(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(q, s, p) at q, continued from the nearer (in the actuators) of the last assembly and the home assembly
        along the straight line of actuator positions, in steps of at most MAX_STEP (one step within a simulation);
        None where the legs stop closing on the way."""
        distances = [float(np.max(np.abs(q - known[0]))) for known in (self._last, self._home)]
        start = self._last if distances[0] <= distances[1] else self._home
        distance = min(distances)
        if distance == 0.0:
            return start
        if distance <= MAX_STEP:    # one step: a simulation's
            solved = self._step(q, start[1], start[2])
            return None if solved is None else (q.copy(), *solved)
        steps = int(np.ceil(distance / MAX_STEP))
        s, p = start[1], start[2]
        for fraction in np.linspace(0.0, 1.0, steps + 1)[1:]:
            solved = self._step(start[0] + fraction * (q - start[0]), s, p)
            if solved is None:
                return None
            s, p = solved
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


def generated_assembly(model: GeneratedModel) -> GeneratedAssembly | None:
    """The generated assembly of a model loaded with the C backend whose C code has one, else None."""
    if not isinstance(model, LoadedModel) or model.backend != "c":
        return None
    try:
        return GeneratedAssembly(model)
    except GeneratedCodeError:
        return None


class ClosureFunctions:
    """The dynamics of legs without closed forms as functions of the actuated joints (see the module docstring).

    Raises:
        GeneratedCodeError: the model lacks ``closure_dynamics`` (no bodies declared), or its legs do not close at
            the home pose; :meth:`function` of the dynamics: ``friction`` is missing where the joints declare it.
    """

    def __init__(self, model: GeneratedModel):
        missing = [name for name in NEEDED if name not in model.functions]
        if missing:
            self._refuse(model, missing + (["friction"] if self._lacks_friction(model) else []))
        self.model = model
        self.assembly = ClosureAssembly(model)
        self.home = self.assembly.home
        #: the names :meth:`function` gives: the plant's, and the actuators' regressors whose closure regressor exists
        self.names = PLANT_FUNCTIONS + tuple(name for name, closure in REGRESSORS.items() if closure in model.functions)
        self._last_dynamics: tuple[np.ndarray, np.ndarray, ActuatedDynamics] | None = None
        self._last_assembly: tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None = None

    @staticmethod
    def _lacks_friction(model: GeneratedModel) -> bool:
        """Whether the joints declare friction the model has no generated ``friction`` for."""
        return "friction" not in model.functions and any(c.viscous is not None for c in model.info.coordinates)

    @staticmethod
    def _refuse(model: GeneratedModel, missing: list[str]) -> None:
        outputs = ",".join(NEEDED + (("friction",) if "friction" in missing else ()))
        raise GeneratedCodeError(f"{model.name}: its legs have no closed forms; simulating them needs the generated "
                                 f"{', '.join(missing)} (declare bodies: links: and platform:, and derive with "
                                 f"--only {outputs})")

    def assembled(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, p) at q (:class:`ClosureAssembly`); of the same q as the last call, that call's (a part of a run
        goes through several regressors: its assemblies are solved once)."""
        q = np.asarray(q, dtype=float)
        last = self._last_assembly
        if last is not None and q.shape == last[0].shape and np.array_equal(q, last[0]):
            return last[1]
        solved = self.assembly(q)
        self._last_assembly = (q.copy(), solved)
        return solved

    def pose(self, q: np.ndarray) -> np.ndarray:
        """The platform pose p (..., m) at q."""
        return self.assembled(q)[1]

    def dynamics(self, q: np.ndarray, qd: np.ndarray) -> ActuatedDynamics:
        """M, the bias efforts, W and the energies at (q, qd); the last state's are kept (a step of the loop asks
        for its acceleration, TCP Jacobian and gravity at one state)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if self._last_dynamics is not None:
            last_q, last_qd, terms = self._last_dynamics
            if q.shape == last_q.shape and np.array_equal(q, last_q) and np.array_equal(qd, last_qd):
                return terms
        s, p = self.assembled(q)
        terms = actuated_dynamics(self.model, q, s, p, qd, self.assembly.generated)
        self._last_dynamics = (q.copy(), qd.copy(), terms)
        return terms

    def _last_at(self, q: np.ndarray) -> bool:
        """Whether the last state's terms are at q."""
        last = self._last_dynamics
        return last is not None and np.shape(q) == last[0].shape and np.array_equal(q, last[0])

    def _at(self, q: np.ndarray, *, at_rest: bool) -> ActuatedDynamics:
        """The terms at q: the last state's when it was at q (M, W and u do not depend on qd) and, ``at_rest``, not
        moving (the bias efforts at qd = 0 are the gravity efforts); else evaluated at qd = 0."""
        last = self._last_dynamics
        if last is not None and self._last_at(q) and not (at_rest and np.any(last[1])):
            return last[2]
        return self.dynamics(q, np.zeros(np.shape(q)))

    def function(self, name: str) -> Callable[..., np.ndarray]:
        """The function ``name`` (one of :attr:`names` but fk: a generated function's name and signature, in the
        joints only).

        Raises:
            GeneratedCodeError: the dynamics asked for lack the generated ``friction`` the joints declare (it
                would silently read as zero).
        """
        if name in WITH_FRICTION and self._lacks_friction(self.model):
            self._refuse(self.model, ["friction"])
        return getattr(self, f"_{name}")

    def _regressor(self, q, qd, qdd):
        return closure_regressor(self.model, q, *self.assembled(q), qd, qdd)

    def _base_regressor(self, q, qd, qdd):
        return closure_regressor(self.model, q, *self.assembled(q), qd, qdd, base=True)

    def _energy_regressor(self, q, qd):
        return closure_energy_regressor(self.model, q, *self.assembled(q), qd)

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
        """J = dp/dq: the p rows of W - of the last state's W at q, else of the generated assembly's Jacobian where
        the model has one (one configuration; a loop step asks for J before the dynamics at the same q), and where
        that is NaN (the actuators do not determine the platform) or there is none, of W at q."""
        generated = self.assembly.generated
        if generated is not None and np.ndim(q) == 1 and not self._last_at(q):
            s, p = self.assembled(q)
            J = generated.jacobian(np.array(q, dtype=float), np.ascontiguousarray(s), np.ascontiguousarray(p))
            if np.all(np.isfinite(J)):
                return J
        W = self._at(q, at_rest=False).W
        return W[..., W.shape[-2] - len(self.model.info.task_space):, :]

"""The generated assembly of a parallel model from Python (issue 63): ``<model>_assemble`` and
``<model>_assembly_jacobian`` of its C library (:mod:`symkin.backends.c.assembly`), bound once for a control loop.

``GeneratedAssembly(load(directory, "c"))`` takes the assembly's functions the C loader bound with the model's library
(:class:`symkin.backends.c.loader_assembly.AssemblyBinding`: through compiled CPython entry points for exact float64
C-contiguous arrays, and otherwise through ctypes with plain pointers, the arrays' checks done here, on their
attributes) and the model's parameter values (its defaults, or a bound design's); :meth:`GeneratedAssembly.assemble`
updates a warm start (s, p) in place - the previous sample's - and :meth:`GeneratedAssembly.jacobian` gives J = dp/dq
(:meth:`GeneratedAssembly.assemble_batch` and :meth:`GeneratedAssembly.jacobian_batch`: K samples in one call);
:class:`RuntimeAssembly` gives the same interface on the run-time solver for a model of any backend (numpy);
:meth:`GeneratedAssembly.actuated_dynamics` the dynamics in the actuated coordinates where the C code has
``closure_dynamics`` (``<model>_actuated_dynamics``: a simulation's step).
A call that does not close the legs leaves NaN and says so (its return value), and a possible jump of assembly mode
is flagged (a negative count), never a silent wrong branch.
"""

from __future__ import annotations

import numpy as np

from symkin.backends.c.assembly import CLOSED
from symkin.backends.c.loader_assembly import ASSEMBLY_FUNCTIONS, closure_vector_sizes
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import GeneratedModel
from symkin.runtime.loader import LoadedModel
from symkin.runtime.parallel import solve_closure

#: The assembly's defaults: the steps allowed and the step that converges (the run-time solver's).
MAX_ITERATIONS, TOLERANCE = 50, 1e-12


class GeneratedAssembly:
    """The generated forward kinematics and J of a model loaded with the C backend (see the module docstring).

    Raises:
        GeneratedCodeError: the model was not loaded with ``backend="c"``, or its C code has no assembly (derive it
            with ``closure`` and ``closure_jacobians`` in the C backend).
    """

    def __init__(self, model: LoadedModel):
        if model.backend != "c":
            raise GeneratedCodeError(f"{model.name}: the generated assembly is C code; load the model with "
                                     f"backend=\"c\" (loaded: {model.backend})")
        if not set(ASSEMBLY_FUNCTIONS) <= set(model.info.functions):
            raise GeneratedCodeError(f"{model.name}: no generated assembly; derive the model with closure and "
                                     "closure_jacobians in the C backend")
        binding = model.assembly_binding
        if binding is None:
            raise GeneratedCodeError(f"{model.name}: its C code predates the generated assembly; derive the model "
                                     "again")
        self._parameters = [float(model.parameters[name]) for name in binding.parameter_names]
        self._parameter_array = np.array(self._parameters, dtype=np.float64)
        self.sizes = binding.sizes
        self._entry = binding.entry
        self._assemble, self._jacobian, self._inverse = binding.assemble, binding.jacobian, binding.inverse
        self._assemble_batch, self._jacobian_batch = binding.assemble_batch, binding.jacobian_batch
        self._residual = np.zeros(1)
        self._residual_address = self._residual.ctypes.data
        self.name = model.name
        self._dynamics = binding.dynamics
        self._dynamics_parameters = [float(model.parameters[name]) for name in binding.dynamics_parameter_names]
        self._dynamics_parameter_array = np.array(self._dynamics_parameters, dtype=np.float64)

    @property
    def compiled(self) -> bool:
        """Whether compiled CPython entry points serve the calls with exact arrays (else ctypes serves every call:
        ``SYMKIN_C_ENTRY=ctypes``, or no Python headers or compiler for the extension)."""
        return self._entry is not None

    def _pointer(self, array: np.ndarray, name: str, writable: bool = False) -> int:
        """The address of a float64 C-contiguous vector of the assembly's size for ``name``, or a clear error."""
        if not (isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.c_contiguous
                and array.shape == (self.sizes[name],) and (array.flags.writeable or not writable)):
            raise ValueError(f"{self.name} assembly: '{name}' must be a{' writable' if writable else ''} float64 "
                             f"C-contiguous array of shape ({self.sizes[name]},), got "
                             f"{getattr(array, 'dtype', type(array).__name__)} {np.shape(array)}")
        return array.ctypes.data

    def _check_batch(self, count: int, arrays: tuple[tuple[str, np.ndarray, bool], ...]) -> None:
        """Each (name, array, writable) a float64 C-contiguous (count, size of name) array (writable where asked), or a
        clear error."""
        for name, array, writable in arrays:
            if not (isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.c_contiguous
                    and array.shape == (count, self.sizes[name]) and (array.flags.writeable or not writable)):
                raise ValueError(f"{self.name} assembly: '{name}' must be a{' writable' if writable else ''} float64 "
                                 f"C-contiguous array of shape ({count}, {self.sizes[name]}), got "
                                 f"{getattr(array, 'dtype', type(array).__name__)} {np.shape(array)}")

    def assemble_batch(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, *, max_iterations: int = MAX_ITERATIONS,
                       tolerance: float = TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`assemble` of K samples in one call (q (K, n); s (K, ns) and p (K, m) the starts, written back into;
        float64 C-contiguous), each from its own start: (steps (K,), max |phi| (K,)) by :meth:`assemble`'s rules."""
        if self._assemble_batch is None:
            raise GeneratedCodeError(f"{self.name}: its C code predates the batched assembly; derive the model again")
        count = len(q)
        self._check_batch(count, (("q", q, False), ("s", s, True), ("p", p, True)))
        steps, residual = np.zeros(count, dtype=np.intc), np.zeros(count)
        self._assemble_batch(count, q.ctypes.data, s.ctypes.data, p.ctypes.data, *self._parameters, max_iterations,
                             tolerance, residual.ctypes.data, steps.ctypes.data)
        return steps, residual

    def jacobian_batch(self, q: np.ndarray, s: np.ndarray, p: np.ndarray) -> np.ndarray:
        """:meth:`jacobian` of K assembled samples in one call (q (K, n), s (K, ns), p (K, m), float64
        C-contiguous): J (K, m, n), NaN where the actuators do not determine the platform."""
        if self._jacobian_batch is None:
            raise GeneratedCodeError(f"{self.name}: its C code predates the batched assembly; derive the model again")
        count = len(q)
        self._check_batch(count, (("q", q, False), ("s", s, False), ("p", p, False)))
        J, determined = np.empty((count, self.sizes["p"], self.sizes["q"])), np.zeros(count, dtype=np.intc)
        self._jacobian_batch(count, q.ctypes.data, s.ctypes.data, p.ctypes.data, *self._parameters, J.ctypes.data,
                             determined.ctypes.data)
        return J

    def assemble(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, *, max_iterations: int = MAX_ITERATIONS,
                 tolerance: float = TOLERANCE) -> tuple[int, float]:
        """Gauss-Newton from the warm start (s, p), written back into them: (steps taken, max |phi|); 0 steps and
        s, p NaN where it did not converge or the legs do not close there; -steps where the legs closed but the
        start was outside its Newton-Kantorovich region (a possible jump of assembly mode: s, p hold the assembly
        reached; :mod:`symkin.backends.c.assembly`)."""
        if self._entry is not None:
            taken = self._entry.assemble(q, s, p, self._parameter_array, max_iterations, tolerance, self._residual)
            if taken is not None:
                return taken, float(self._residual[0])
        steps = self._assemble(self._pointer(q, "q"), self._pointer(s, "s", True), self._pointer(p, "p", True),
                               *self._parameters, max_iterations, tolerance, self._residual_address)
        return steps, float(self._residual[0])

    @property
    def has_inverse(self) -> bool:
        """Whether the C code holds the generated inverse (``<model>_assemble_inverse``; code derived before it has
        none)."""
        return self._inverse is not None

    def assemble_inverse(self, p: np.ndarray, q: np.ndarray, s: np.ndarray, *, max_iterations: int = MAX_ITERATIONS,
                         tolerance: float = TOLERANCE, max_step: float | None = None, stall: int | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
        """Gauss-Newton for the actuated and passive joints at each pose p (K, m) from the starts q (K, n) and
        s (K, ns), written back into them (float64 C-contiguous): (steps (K,), max |phi| (K,)), 0 steps and q, s NaN
        where a sample did not converge - :func:`symkin.newton.newton_iterate`'s rules (``max_step`` shortens a
        step, ``stall`` gives up on a residual that stagnates) in one call for the batch."""
        if self._inverse is None:
            raise GeneratedCodeError(f"{self.name}: its C code predates the generated inverse; derive the model again")
        count = len(p)
        self._check_batch(count, (("p", p, False), ("q", q, True), ("s", s, True)))
        steps, residual = np.zeros(count, dtype=np.intc), np.zeros(count)
        self._inverse(count, p.ctypes.data, q.ctypes.data, s.ctypes.data, *self._parameters, max_iterations, tolerance,
                      0.0 if max_step is None else max_step, stall or 0, residual.ctypes.data, steps.ctypes.data)
        return steps, residual

    def jacobian(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """J = dp/dq (task x actuated) at an assembled (q, s, p); NaN where the actuators do not determine the
        platform.  ``out``: a float64 C-contiguous array of that shape to write into."""
        shape = (self.sizes["p"], self.sizes["q"])
        J = np.empty(shape) if out is None else out
        if not (J.dtype == np.float64 and J.flags.c_contiguous and J.shape == shape and J.flags.writeable):
            raise ValueError(f"{self.name} assembly: out= must be a writable float64 C-contiguous array of shape "
                             f"{shape}, got {J.dtype} {J.shape}")
        if self._entry is not None and self._entry.jacobian(q, s, p, self._parameter_array, J) is not None:
            return J
        self._jacobian(self._pointer(q, "q"), self._pointer(s, "s"), self._pointer(p, "p"), *self._parameters,
                       J.ctypes.data)
        return J

    @property
    def has_dynamics(self) -> bool:
        """Whether the C code holds ``<model>_actuated_dynamics`` (a model with closure_dynamics in C, derived since)."""
        return self._dynamics is not None

    def actuated_dynamics(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, qd: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float] | None:
        """(M, bias, W, drift, u) at an assembled (q, s, p) moving at qd (float64 C-contiguous vectors):
        ``<model>_actuated_dynamics`` (:func:`symkin.runtime.closure_dynamics.actuated_dynamics`' terms but the
        friction); None where the C code has none or [Phi_s Phi_p] has a dependent column (a singularity)."""
        if self._dynamics is None:
            return None
        n, N = self.sizes["q"], sum(self.sizes.values())
        M, bias, W, drift, u = np.empty((n, n)), np.empty(n), np.empty((N, n)), np.empty(N), np.empty(1)
        solved = None if self._entry is None else self._entry.dynamics(q, s, p, qd, self._dynamics_parameter_array,
                                                                        M, bias, W, drift, u)
        if solved is None:
            solved = self._dynamics(self._pointer(q, "q"), self._pointer(s, "s"), self._pointer(p, "p"),
                                    self._pointer(qd, "q"), *self._dynamics_parameters, M.ctypes.data,
                                    bias.ctypes.data, W.ctypes.data, drift.ctypes.data, u.ctypes.data)
        return (M, bias, W, drift, float(u[0])) if solved else None


class RuntimeAssembly:
    """:class:`GeneratedAssembly`'s interface on the run-time solver, for a model loaded with any backend (numpy
    batched): :meth:`assemble` and :meth:`assemble_batch` by Gauss-Newton on the generated closure
    (:func:`symkin.runtime.parallel.solve_closure`, unknowns p and s, from the given starts, written back into them)
    with the C assembly's contract - the steps taken, 0 and NaN where it did not converge or the legs do not close
    (max |phi| above :data:`symkin.backends.c.assembly.CLOSED` max(1, |p|)), -steps where a correction above the
    tolerance failed to halve the one before (a possible jump of assembly mode) - and :meth:`jacobian` and
    :meth:`jacobian_batch`: J = dp/dq, the p-part of the least-squares solution of [Phi_s Phi_p] (ds, dp) = -Phi_q dq,
    NaN where the actuators do not determine the platform (rank [Phi_s Phi_p] < rank Phi_s + m, numerical ranks by
    the SVD at rows eps times the largest singular value).  The same answers as the C code's to the solvers'
    rounding, without a compiler.

    Raises:
        GeneratedCodeError: the model lacks ``closure`` or ``closure_jacobians``.
    """

    def __init__(self, model: GeneratedModel):
        missing = [name for name in ASSEMBLY_FUNCTIONS if name not in model.functions]
        if missing:
            raise GeneratedCodeError(f"{model.name}: no closure to assemble; derive the model with "
                                     f"{', '.join(missing)}")
        self.model = model
        self.name = model.name
        self.sizes = closure_vector_sizes(model.info)

    def assemble(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, *, max_iterations: int = MAX_ITERATIONS,
                 tolerance: float = TOLERANCE) -> tuple[int, float]:
        """Gauss-Newton from the warm start (s, p), written back into them: (steps, max |phi|) by
        :class:`GeneratedAssembly.assemble`'s contract."""
        s_batch, p_batch = s[None].copy(), p[None].copy()
        steps, residual = self.assemble_batch(np.asarray(q, dtype=float)[None], s_batch, p_batch,
                                              max_iterations=max_iterations, tolerance=tolerance)
        s[...], p[...] = s_batch[0], p_batch[0]
        return int(steps[0]), float(residual[0])

    def assemble_batch(self, q: np.ndarray, s: np.ndarray, p: np.ndarray, *, max_iterations: int = MAX_ITERATIONS,
                       tolerance: float = TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`assemble` of K samples (q (K, n); the starts s (K, ns) and p (K, m), written back into), each from
        its own start: (steps (K,), max |phi| (K,))."""
        report = solve_closure(self.model, q, s, p, unknowns=("p", "s"), tol=tolerance, max_iterations=max_iterations)
        solution = report.solution
        assert isinstance(solution, dict), "solve_closure names its vectors"
        scale = np.maximum(1.0, np.max(np.abs(np.nan_to_num(solution["p"], nan=0.0)), axis=-1))
        closed = report.converged & (report.residual <= CLOSED * scale)
        s[...] = np.where(closed[:, None], solution["s"], np.nan)
        p[...] = np.where(closed[:, None], solution["p"], np.nan)
        assert report.left_region is not None, "newton_iterate watches the corrections"
        steps = np.where(closed, np.where(report.left_region, -report.iterations, report.iterations), 0)
        return steps.astype(np.intc), np.asarray(report.residual, dtype=float)

    def jacobian(self, q: np.ndarray, s: np.ndarray, p: np.ndarray) -> np.ndarray:
        """J = dp/dq (m, n) at an assembled (q, s, p); NaN where the actuators do not determine the platform."""
        return self.jacobian_batch(np.asarray(q, dtype=float)[None], np.asarray(s, dtype=float)[None],
                                   np.asarray(p, dtype=float)[None])[0]

    def jacobian_batch(self, q: np.ndarray, s: np.ndarray, p: np.ndarray) -> np.ndarray:
        """:meth:`jacobian` of K assembled samples: J (K, m, n)."""
        blocks = self.model.closure_jacobians(q, s, p)
        Phi_q, Phi_s, Phi_p = (np.asarray(b, dtype=float).reshape(len(q), -1, b.shape[-1])
                               for b in (blocks.Phi_q, blocks.Phi_s, blocks.Phi_p))
        A = np.concatenate([Phi_s, Phi_p], axis=-1)
        J = np.full((len(q), Phi_p.shape[-1], Phi_q.shape[-1]), np.nan)
        finite = np.all(np.isfinite(A), axis=(-2, -1)) & np.all(np.isfinite(Phi_q), axis=(-2, -1))
        if np.any(finite):
            rows = A.shape[-2]
            rank = _numerical_rank(A[finite], rows)
            determined = rank == _numerical_rank(Phi_s[finite], rows) + Phi_p.shape[-1]
            solved = -np.linalg.pinv(A[finite]) @ Phi_q[finite]
            J[np.flatnonzero(finite)[determined]] = solved[determined][:, Phi_s.shape[-1]:]
        return J


def _numerical_rank(A: np.ndarray, rows: int) -> np.ndarray:
    """The numerical rank of each matrix of the batch A (k, r, c): its singular values above rows eps times the
    largest (the C assembly's rank test)."""
    if A.shape[-1] == 0:
        return np.zeros(len(A), dtype=int)
    singular = np.linalg.svd(A, compute_uv=False)
    return np.count_nonzero(singular > rows * np.finfo(float).eps * singular[:, :1], axis=-1)

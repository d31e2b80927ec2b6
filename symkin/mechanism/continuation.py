"""Assembly continued over the handle's positions: how a mechanism without closed forms reaches its poses (issue 31;
issue 62: the general method, in the run-time mechanism that every analysis asks).

Legs without the distance form (the two SCARA legs of docs/model-format.md, "Legs of any topology") have no
closed-form ``ik`` or ``fk``: the generated ``closure`` phi(q, s, p) = 0 and ``closure_jacobians`` are all there
is.  What they reach is the *working mode* of the home assembly, the aspect of Wenger and Chablat (1998): the
task poses connected to the home pose without crossing a singularity of either type, with the actuators and the
declared passive joints within their limits.  The platform's positions (the x, y, z of its task space) are
gridded with its angles held (a constant orientation, as for the Stewart-Gough platform), and the grid is
flooded from the cell nearest the home pose (:func:`continued_grid`): a cell is solved for (q, s) by
Gauss-Newton (:func:`symkin.runtime.parallel.solve_closure`) from a reached face neighbour and is reached when

* the solve converges (the legs close there),
* the actuators and the declared passive joints are within their limits, and
* no singularity lies between the two cells: det(T_a^T T_b) > 0 and det(A_a^T A_b) > 0 for the closure's
  blocks T = P Phi_p and A = P Phi_q seen by the constraints the passive joints cannot take up
  (:func:`symkin.runtime.parallel.closure_frames`): crossing an interior singularity (a change of assembly mode)
  reverses T, crossing a boundary one (a leg changing branch) reverses A.

A part of the workspace thinner than a cell, or joined to the rest only through one, is missed: the cell size
is the resolution.  The grid's box is found by coarse floods from a box around the home pose, doubled on every
side its reached cells touch, and the fine grid grows where its reached cells still touch its box; a workspace
that still touches it after :data:`BOX_DOUBLINGS` doublings and :data:`BOX_GROWTHS` growths is reported
unbounded (a prismatic actuator with limits far beyond the rest of the mechanism).  :func:`flood_box` floods a
given box only, :func:`continue_from` follows straight paths from one assembly.

Conditioning (:func:`conditioning_at`): 1/kappa of J = dp/dq (:func:`symkin.runtime.parallel.closure_velocities`),
its angle rows as angular velocity (:func:`angular_rates`), its position rows divided by a characteristic length
L where the task space also has angles (given, or the L minimizing the mean kappa_F^2 over the poses:
:func:`symkin.numerics.conditioning.characteristic_length`).  The analyses of such a workspace (its measure, its
GCI) are :mod:`symkin.analysis.continued_workspace`.

Length: one method - the flood, the search for its box, the paths and the conditioning at the cells it reaches -
whose parts only make sense together.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin import mechanism, reporting
from symkin.mechanism import Limits, passive
from symkin.mechanism.closure import (MAX_STEP, SOLVE_ITERATIONS, SOLVE_TOLERANCE, HomeAssembly, closes,
                                      closure_sizes, generated_assembly, solve_home_assembly, uses_closure)
from symkin.newton import NewtonReport
from symkin.numerics import conditioning, sampling
from symkin.runtime.assembly import GeneratedAssembly
from symkin.runtime.info import GeneratedModel
from symkin.runtime.parallel import ClosureFrames, closure_frames, closure_velocities, solve_closure

#: Cells along the longest side of the workspace's grid.
CELLS = 32
#: Cells along each side of the coarse grids that find the workspace's box ...
BOX_CELLS = 12
#: ... which doubles at most this many times on the sides its reached cells touch (the coarse cells stay within
#: what Gauss-Newton crosses from a neighbour, SOLVE_ITERATIONS * MAX_STEP, for a workspace within a few metres);
BOX_DOUBLINGS = 4
#: the fine grid grows by half its width on a side its reached cells touch, at most this many times.
BOX_GROWTHS = 3
#: The flood starts from the nearest of the SEEDS ** d cells around the home pose that it reaches.
SEEDS = 3
#: Largest change of a held angle (rad) per step of the path from the home pose to the first cell.
ANGLE_STEP = 0.05
#: A solve from a neighbour gives up once its residual stagnates over this many steps (a cell beyond the workspace:
#: :func:`symkin.newton.newton_iterate`'s ``stall``); from a cell a step away Gauss-Newton's residual falls at every
#: step.
STALL = 4


def _same_side(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Boolean (K,): det(a^T b) > 0 for stacks a, b (K, rows, c); False where either is NaN."""
    with np.errstate(invalid="ignore"):
        return np.linalg.det(np.nan_to_num(np.swapaxes(a, -1, -2) @ b, nan=0.0)) > 0 if len(a) else np.zeros(0, bool)


def _limits(model: GeneratedModel, limits: Limits | None) -> passive.AssemblyLimits:
    """What a continued assembly keeps: the actuators' limits (given, or the model's with a turn for a revolute joint
    without any) and the declared passive-joint limits."""
    return passive.AssemblyLimits(mechanism.joint_limits(model, limits), mechanism.revolute_mask(model),
                                  passive.declared_limits(model))


def _inverse(model: GeneratedModel) -> GeneratedAssembly | None:
    """The generated inverse of a model loaded with the C backend (``<model>_assemble_inverse``), else None."""
    generated = generated_assembly(model)
    return generated if generated is not None and generated.has_inverse else None


def _solve(model: GeneratedModel, q: np.ndarray, s: np.ndarray, p: np.ndarray,
           inverse: GeneratedAssembly | None) -> NewtonReport:
    """(q, s) at the poses p (K, m) by Gauss-Newton from the neighbouring (q, s): by the generated inverse in one
    call for the batch where there is one, else by the run-time solver - the same rules
    (:func:`symkin.newton.newton_iterate`: the step shortened to MAX_STEP, a stagnating residual given up)."""
    if inverse is None:
        return solve_closure(model, q, s, p, unknowns=("q", "s"), tol=SOLVE_TOLERANCE,
                             max_iterations=SOLVE_ITERATIONS, max_step=MAX_STEP, stall=STALL)
    q, s = np.array(q, dtype=float, order="C"), np.array(s, dtype=float, order="C")
    p = np.ascontiguousarray(p, dtype=float)
    steps, residual = inverse.assemble_inverse(p, q, s, max_iterations=SOLVE_ITERATIONS, tolerance=SOLVE_TOLERANCE,
                                               max_step=MAX_STEP, stall=STALL)
    return NewtonReport({"q": q, "s": s, "p": p}, steps > 0, steps, residual, np.full(len(p), np.nan))


def _advance(model: GeneratedModel, q: np.ndarray, s: np.ndarray, frames: ClosureFrames, p: np.ndarray,
             limits: passive.AssemblyLimits, inverse: GeneratedAssembly | None
             ) -> tuple[np.ndarray, np.ndarray, ClosureFrames, np.ndarray]:
    """(q, s, their closure frames, taken) at the poses p (K, m) solved from the neighbouring solutions (q, s)
    whose closure frames are ``frames`` (:func:`_solve`): taken where the solve converged within the limits and
    crossed no singularity.  The frames returned serve the next step from these solutions (computed once per
    solve)."""
    report = _solve(model, q, s, p, inverse)
    solution = report.solution
    assert isinstance(solution, dict), "solve_closure names its vectors"
    q1, s1 = solution["q"], solution["s"]
    after = closure_frames(model, q1, s1, p)
    taken = (closes(report, p) & _same_side(frames.task, after.task) & _same_side(frames.actuated, after.actuated))
    taken[taken] &= limits.hold(q1[taken], s1[taken])
    return q1, s1, after, taken


def _march(model: GeneratedModel, start: tuple[np.ndarray, np.ndarray, np.ndarray], targets: np.ndarray,
           cell: float, limits: passive.AssemblyLimits) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, s, taken) at the poses ``targets`` (K, m) continued along straight paths from the assembly
    start = (q, s, p) (one assembly, or one per target: (K, n), (K, ns), (K, m)) in steps of at most a cell
    (positions) and :data:`ANGLE_STEP` (angles); taken is False where a path leaves the working mode (a limit, a
    singularity, legs that do not close)."""
    positions = np.array([c in mechanism.POSITION_COMPONENTS for c in mechanism.task_space(model)])
    q, s, p0 = (np.array(np.broadcast_to(v, (len(targets), np.shape(v)[-1]))) for v in start)
    change = np.abs(targets - p0).max(axis=0, initial=0.0)
    steps = int(max(np.ceil(change[positions].max(initial=0.0) / cell),
                    np.ceil(change[~positions].max(initial=0.0) / ANGLE_STEP), 1))
    taken = np.ones(len(targets), dtype=bool)
    frames = closure_frames(model, q, s, p0)
    inverse = _inverse(model)
    for done, t in enumerate(np.linspace(0.0, 1.0, steps + 1)[1:]):
        reporting.report_progress("continuing the closure (steps)", done=done, total=steps)
        q, s, frames, step_taken = _advance(model, q, s, frames, p0 + t * (targets - p0), limits, inverse)
        taken &= step_taken
    return q, s, taken


@dataclass(frozen=True)
class _Flood:
    """Which cells of a grid the working mode reaches, and their (q, s) (NaN elsewhere), flattened."""

    reached: np.ndarray
    q: np.ndarray
    s: np.ndarray


def _flood(model: GeneratedModel, poses: np.ndarray, shape: tuple[int, ...], seed: int, seed_solution: tuple,
           limits: passive.AssemblyLimits) -> _Flood:
    """Breadth-first over the face neighbours of a grid of poses (prod(shape), m) from the reached cell
    ``seed``: each layer solves every unreached neighbour of the last layer from one of its reached
    neighbours in one batch (:func:`_advance`)."""
    n, ns = closure_sizes(model)
    reached = np.zeros(len(poses), dtype=bool)
    q, s = np.full((len(poses), n), np.nan), np.full((len(poses), ns), np.nan)
    reached[seed], q[seed], s[seed] = True, seed_solution[0], seed_solution[1]
    frontier = np.array([seed])  # sorted, as np.unique leaves each layer's cells
    frontier_frames = closure_frames(model, q[frontier], s[frontier], poses[frontier])
    inverse = _inverse(model)
    while len(frontier):
        reporting.report_progress(f"flooding a grid of {len(poses)} cells (cells reached)", done=int(reached.sum()))
        index = np.array(np.unravel_index(frontier, shape)).T
        candidates, parents = [], []
        for axis in range(len(shape)):
            for offset in (-1, 1):
                neighbour = index.copy()
                neighbour[:, axis] += offset
                inside = (neighbour[:, axis] >= 0) & (neighbour[:, axis] < shape[axis])
                candidates.append(np.ravel_multi_index(tuple(neighbour[inside].T), shape))
                parents.append(frontier[inside])
        cells, parent = np.concatenate(candidates), np.concatenate(parents)
        fresh = ~reached[cells]
        cells, first = np.unique(cells[fresh], return_index=True)
        parent = parent[fresh][first]
        if not len(cells):
            break
        at = np.searchsorted(frontier, parent)  # the parents are cells of the last layer, whose frames are known
        frames = ClosureFrames(frontier_frames.task[at], frontier_frames.actuated[at])
        q1, s1, after, taken = _advance(model, q[parent], s[parent], frames, poses[cells], limits, inverse)
        frontier = cells[taken]
        frontier_frames = ClosureFrames(after.task[taken], after.actuated[taken])
        reached[frontier], q[frontier], s[frontier] = True, q1[taken], s1[taken]
    return _Flood(reached, q, s)


@dataclass(frozen=True)
class _Grid:
    """A grid over the positions of ``template`` (the held pose): its occupancy geometry and flattened poses."""

    lower: np.ndarray
    cell: np.ndarray
    shape: tuple[int, ...]
    poses: np.ndarray


def _grid(template: np.ndarray, positions: np.ndarray, lower: np.ndarray, cell: np.ndarray,
          shape: tuple[int, ...]) -> _Grid:
    centres = sampling.cell_centres(lower, cell, shape).reshape(-1, len(shape))
    poses = np.repeat(template[None, :], len(centres), axis=0)
    poses[:, positions] = centres
    return _Grid(lower, cell, shape, poses)


def _flood_grid(model: GeneratedModel, grid: _Grid, positions: np.ndarray, home: tuple, limits: passive.AssemblyLimits) -> _Flood:
    """Flood ``grid`` from the cell nearest the home pose among the :data:`SEEDS` ** d nearest that a straight
    path from the home assembly reaches in the working mode (the nearest may lie beyond a limit the home pose
    is close to)."""
    distance = np.linalg.norm(grid.poses[:, positions] - home[2][positions], axis=-1)
    nearest = np.argsort(distance, kind="stable")[:SEEDS ** len(grid.shape)]
    q, s, taken = _march(model, home, grid.poses[nearest], float(grid.cell.min()), limits)
    if not taken.any():
        raise ValueError(f"{model.name}: the legs cannot be moved from the home pose {home[2].tolist()} to any of the "
                         f"{len(nearest)} grid cells nearest it without leaving their limits or crossing a "
                         "singularity: is the home pose inside the limits?")
    first = int(np.argmax(taken))
    return _flood(model, grid.poses, grid.shape, int(nearest[first]), (q[first], s[first]), limits)


def _touched_sides(reached: np.ndarray) -> np.ndarray:
    """Boolean (d, 2): whether the reached cells touch each grid's lower and upper face along each axis."""
    return np.array([[np.take(reached, end, axis=axis).any() for end in (0, -1)] for axis in range(reached.ndim)])


def _unbounded(model: GeneratedModel, lower: np.ndarray, upper: np.ndarray) -> ValueError:
    axes = [c for c in mechanism.task_space(model) if c in mechanism.POSITION_COMPONENTS]
    return ValueError(f"{model.name}: the workspace at this orientation still reaches the edge of a box "
                      f"{(upper - lower).round(6).tolist()} m wide ({', '.join(axes)}): it is unbounded within the "
                      "joint limits; declare limits on the prismatic joints (or pass --limit)")


def _box(model: GeneratedModel, template: np.ndarray, positions: np.ndarray, home: tuple,
         limits: passive.AssemblyLimits) -> tuple[np.ndarray, np.ndarray]:
    """A first box (lower, upper) around the working mode's positions: coarse floods (:data:`BOX_CELLS` a side)
    from a box around the home pose, doubled on the sides its reached cells touch, then shrunk to them."""
    centre = template[positions]
    half = np.full(len(centre), max(float(np.linalg.norm(centre)), 1e-3))
    lower, upper = centre - half, centre + half
    for _ in range(BOX_DOUBLINGS + 1):
        grid = _grid(template, positions, lower, (upper - lower) / BOX_CELLS, (BOX_CELLS,) * len(lower))
        reached = _flood_grid(model, grid, positions, home, limits).reached.reshape(grid.shape)
        touched = _touched_sides(reached)
        if not touched.any():
            index = np.array(np.nonzero(reached))
            return grid.lower + (index.min(axis=1) - 1) * grid.cell, grid.lower + (index.max(axis=1) + 2) * grid.cell
        width = upper - lower
        lower, upper = lower - touched[:, 0] * width, upper + touched[:, 1] * width
    raise _unbounded(model, lower, upper)


def angular_rates(model: GeneratedModel, J: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """J (..., m, n) at the task poses (..., m) with its roll-pitch-yaw rows turned into angular velocity (base frame,
    E of each pose: :func:`symkin.mechanism.reach.angular_velocity_matrix`) where the task space has all three (so
    kappa does not depend on the angles' parametrization); a single angle (planar yaw) is a rate already."""
    from symkin.mechanism.reach import angular_velocity_matrix

    task = mechanism.task_space(model)
    if not set(mechanism.ANGLES) <= set(task):
        return J
    rows = np.array([task.index(c) for c in mechanism.ANGLES])
    rates = np.broadcast_to(np.eye(len(task)), J.shape[:-2] + (len(task), len(task))).copy()
    rates[..., rows[:, None], rows[None, :]] = angular_velocity_matrix(np.asarray(poses)[..., rows])
    return rates @ J


def handle_jacobian(model: GeneratedModel, q: np.ndarray, s: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """J = dp/dq (K, m, n) at the assembled (q, s, p) (:func:`symkin.runtime.parallel.closure_velocities`), its angle
    rows as angular velocity (:func:`angular_rates`)."""
    return angular_rates(model, closure_velocities(model, q, s, poses).J, poses)


def dynamics_at_rest(model: GeneratedModel, q: np.ndarray, s: np.ndarray, poses: np.ndarray) -> Any:
    """The dynamics of the actuated joints at the assembled (q, s, p), not moving (M = W^T M_z W, the bias efforts
    at rest: the gravity efforts, the energies; :func:`symkin.runtime.closure_dynamics.actuated_dynamics`), from the
    generated ``closure_dynamics``."""
    from symkin.runtime.closure_dynamics import actuated_dynamics

    return actuated_dynamics(model, q, s, poses, np.zeros_like(q))


@dataclass(frozen=True)
class AssembledConditioning:
    """1/kappa at assembled poses (:func:`conditioning_at`).

    Attributes:
        inv_kappa: (K,) 1/kappa of J with its position rows divided by ``length`` (0 where J is not determined).
        J: (K, m, n) dp/dq, its angle rows as angular velocity (:func:`angular_rates`), not homogenized.
        length: the characteristic length used (None: the task space has no angles).
    """

    inv_kappa: np.ndarray
    J: np.ndarray
    length: float | None


def conditioning_at(model: GeneratedModel, q: np.ndarray, s: np.ndarray, poses: np.ndarray,
                         length: float | None = None) -> AssembledConditioning:
    """1/kappa of J = dp/dq (:func:`symkin.runtime.parallel.closure_velocities`) at the assembled (q, s, p) (K, .):
    where the task space also has angles, its position rows divided by the characteristic length (given, or the
    one minimizing the mean kappa_F^2 over these poses, :func:`symkin.numerics.conditioning.characteristic_length`)."""
    task = mechanism.task_space(model)
    rows = mechanism.position_rows(model)
    J = handle_jacobian(model, q, s, poses)
    determined = np.all(np.isfinite(J), axis=(-2, -1))
    homogeneous = np.nan_to_num(J)
    if len(rows) < len(task):
        length = length if length is not None else conditioning.characteristic_length(J[determined], rows)
        homogeneous = conditioning.homogenize(homogeneous, length, rows)
    else:
        length = None
    values = np.where(determined, conditioning.inverse_condition_number(homogeneous), 0.0) if len(J) else np.zeros(0)
    return AssembledConditioning(values, J, length)


@dataclass(frozen=True)
class ContinuedGrid:
    """The working mode of the home assembly at a constant orientation, on a grid (:func:`continued_grid`).

    Attributes:
        lower, cell: the grid's corner and cell sizes over the positions of the axes ``axes``.
        reached: which cells the working mode reaches, the grid's shape.
        inv_kappa: 1/kappa at the cell centres, the grid's shape, NaN outside the workspace (0 at a cell whose
            J is not determined, an interior singularity to rounding).
        J: dp/dq at the cell centres, (*shape, m, n), its angle rows as angular velocity
            (:func:`angular_rates`), not homogenized; NaN outside the workspace.
        q: the actuators' coordinates at the cell centres, (*shape, n), NaN outside.
        s: the passive joints' variables there, (*shape, ns), NaN outside.
        pose: the task pose held (the held angles; the positions are the cells').
        axes: the gridded task coordinates, e.g. ("x", "y", "z").
        length: the characteristic length of the conditioning (None: the task space has no angles).
        box: (lower, upper) of the positions the grid was laid over (another grid over the same box:
            ``continued_grid(..., box=found.box)``).
        home: the home assembly solved for the grid (:func:`symkin.mechanism.closure.solve_home_assembly`), or None
            where the grid was continued from a given ``start``.
    """

    lower: np.ndarray
    cell: np.ndarray
    reached: np.ndarray
    inv_kappa: np.ndarray
    J: np.ndarray
    q: np.ndarray
    s: np.ndarray
    pose: np.ndarray
    axes: tuple[str, ...]
    length: float | None
    box: tuple[np.ndarray, np.ndarray]
    home: HomeAssembly | None = None

    def centres(self) -> np.ndarray:
        """The positions of the cell centres, (*shape, d)."""
        return sampling.cell_centres(self.lower, self.cell, self.reached.shape)


def continued_grid(model: GeneratedModel, *, orientation: dict[str, float] | None = None,
                   limits: Limits | None = None, length: float | None = None, cells: int = CELLS,
                   start: tuple[np.ndarray, np.ndarray] | None = None,
                   box: tuple[np.ndarray, np.ndarray] | None = None) -> ContinuedGrid:
    """The working mode of the home assembly at a constant orientation, on a grid of the handle's positions (see the
    module docstring).

    Args:
        model: a parallel model analysed through its closure (:func:`uses_closure`).
        orientation: the held angles by name (e.g. {"yaw": 0.3}); the home pose's for the others.
        limits: the actuators' limit overrides (:func:`symkin.mechanism.joint_limits`).
        length: the characteristic length (m); default: computed over the reached cells.
        cells: cells along the longest side of the grid.
        start: (q, s) of the home assembly; default :func:`symkin.mechanism.closure.solve_home_assembly`'s.
        box: (lower, upper) of the positions to grid, e.g. another grid's ``box``; default: found by coarse
            floods from the home pose.  The grid still grows where its reached cells touch the box.

    Raises:
        ValueError: the model has no closure to continue, an orientation names no angle of its task space, the
            home pose is out of reach, or the workspace is unbounded.
    """
    if not uses_closure(model):
        raise ValueError(f"{model.name}: not a parallel model analysed through its loop closure (it needs the "
                         "generated closure and closure_jacobians, and has a closed-form ik)")
    task = mechanism.task_space(model)
    positions = np.array([c in mechanism.POSITION_COMPONENTS for c in task])
    unknown = set(orientation or {}) - {c for c in task if c not in mechanism.POSITION_COMPONENTS}
    if unknown:
        raise ValueError(f"{model.name}: the orientation names {sorted(unknown)}, which are not angles of its task "
                         f"space {list(task)}")
    home_pose = mechanism.home_pose(model)
    template = home_pose.copy()
    for name, value in (orientation or {}).items():
        template[task.index(name)] = float(value)
    home_assembly = None
    if start is None:
        home_assembly = solve_home_assembly(model)
        q0, s0 = home_assembly.q, home_assembly.s
    else:
        q0, s0 = np.asarray(start[0], float), np.asarray(start[1], float)
    bounds = _limits(model, limits)
    home = (q0, s0, home_pose)
    if box is None:
        lower, upper = _box(model, template, positions, home, bounds)
    else:
        lower, upper = np.asarray(box[0], dtype=float), np.asarray(box[1], dtype=float)
    for _ in range(BOX_GROWTHS + 1):  # a coarse flood can miss a thin part; the fine grid must not touch its box
        corner, size, counts = sampling.grid_geometry(lower, upper, float(np.max(upper - lower)) / cells)
        grid = _grid(template, positions, corner, size, counts)
        flood = _flood_grid(model, grid, positions, home, bounds)
        touched = _touched_sides(flood.reached.reshape(grid.shape))
        if not touched.any():
            break
        width = upper - lower
        lower, upper = lower - touched[:, 0] * width / 2, upper + touched[:, 1] * width / 2
    else:
        raise _unbounded(model, lower, upper)
    reached = flood.reached
    n, ns = closure_sizes(model)
    inv_kappa = np.full(len(reached), np.nan)
    rates = np.full((len(reached), len(task), n), np.nan)
    local = conditioning_at(model, flood.q[reached], flood.s[reached], grid.poses[reached], length)
    rates[reached], inv_kappa[reached] = local.J, local.inv_kappa
    axes = tuple(c for c in task if c in mechanism.POSITION_COMPONENTS)
    return ContinuedGrid(grid.lower, grid.cell, reached.reshape(grid.shape), inv_kappa.reshape(grid.shape),
                         rates.reshape(grid.shape + (len(task), n)), flood.q.reshape(grid.shape + (n,)),
                         flood.s.reshape(grid.shape + (ns,)), template, axes, local.length, (lower, upper),
                         home_assembly)


@dataclass(frozen=True)
class BoxFlood:
    """The working mode's cells of a grid over a box of positions (:func:`flood_box`), flattened.

    Attributes:
        poses: (K, m) the grid's task poses (its positions; the held angles of the home pose).
        reached: (K,) whether the flood from the home assembly reached the pose through the grid.
        q, s: (K, n), (K, ns) the assembly there (NaN where not reached).
        shape: the grid's points per position axis.
    """

    poses: np.ndarray
    reached: np.ndarray
    q: np.ndarray
    s: np.ndarray
    shape: tuple[int, ...]


def flood_box(model: GeneratedModel, lower: np.ndarray, upper: np.ndarray, counts: Sequence[int], *,
              start: tuple[np.ndarray, np.ndarray], vertices: bool = False, limits: Limits | None = None) -> BoxFlood:
    """The working mode of the home assembly ``start`` = (q, s) on a grid over the box [lower, upper] of the
    task's positions, at the home pose's angles, flooded from the home pose through the grid's own cells only (a
    cell joined to the rest only outside the box counts as not reached: the box is asked to be reachable in one
    piece).  ``counts`` points per axis, at the cells' midpoints or (``vertices``) on the box's vertex grid with its
    corners; an axis of one point lies at its box centre (a slice).  Nothing is reached when no straight path from
    the home pose reaches the grid's cells nearest it."""
    task = mechanism.task_space(model)
    positions = np.array([c in mechanism.POSITION_COMPONENTS for c in task])
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    points = np.asarray(counts, dtype=int)
    single = points == 1
    on_vertices = vertices & ~single
    width: np.ndarray = np.where(on_vertices, (upper - lower) / np.maximum(points - 1, 1), (upper - lower) / points)
    cell: np.ndarray = np.where(width > 0, width, np.max(width))  # a slice's axis: a cell as wide as the others
    corner = np.where(on_vertices, lower - cell / 2, np.where(single, (lower + upper) / 2 - cell / 2, lower))
    shape = tuple(int(c) for c in points)
    home_pose = mechanism.home_pose(model)
    grid = _grid(home_pose, positions, corner, cell, shape)
    bounds = _limits(model, limits)
    try:
        flood = _flood_grid(model, grid, positions, (np.asarray(start[0], float), np.asarray(start[1], float),
                                                     home_pose), bounds)
    except ValueError:  # no path from the home pose into the grid
        n, ns = closure_sizes(model)
        flood = _Flood(np.zeros(len(grid.poses), bool), np.full((len(grid.poses), n), np.nan),
                       np.full((len(grid.poses), ns), np.nan))
    return BoxFlood(grid.poses, flood.reached, flood.q, flood.s, shape)


def continue_from(model: GeneratedModel, start: tuple[np.ndarray, np.ndarray, np.ndarray], targets: np.ndarray, *,
                  step: float, limits: Limits | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, s, taken) at the task poses ``targets`` (K, m), each continued along a straight path from the
    assembly start = (q, s, p) in steps of at most ``step`` (m; angles :data:`ANGLE_STEP`); taken is False where a
    path leaves the working mode (a limit, a singularity, legs that do not close)."""
    bounds = _limits(model, limits)
    return _march(model, start, np.asarray(targets, dtype=float), step, bounds)


def continue_from_home(model: GeneratedModel, targets: np.ndarray, *, step: float, limits: Limits | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`continue_from` the home assembly at the home pose (:func:`symkin.mechanism.closure.solve_home_assembly`).

    Raises:
        ValueError: the legs do not close at the home pose.
    """
    home = solve_home_assembly(model)
    return continue_from(model, (home.q, home.s, mechanism.home_pose(model)), targets, step=step, limits=limits)


def home_along_designs(model: GeneratedModel, start: dict[str, float], design: dict[str, float],
                       steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(q, s) of the home assembly of ``design`` (all parameter values; ``model`` unbound): the ``start`` design's
    (:func:`symkin.mechanism.closure.solve_home_assembly`) continued along the straight line of designs in ``steps``
    steps, Gauss-Newton at the home pose from the last step's, so that every design stays in the start design's
    assembly mode (a fresh multi-start assembly may pick another).

    Raises:
        ValueError: the legs stop closing at the home pose on the way (a design that does not reach it).
    """
    home = mechanism.home_pose(model)
    assembly = solve_home_assembly(model.bind(**start))
    q, s = assembly.q, assembly.s
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        values = {name: (1 - t) * start[name] + t * design[name] for name in design}
        report = solve_closure(model.bind(**values), q, s, home, unknowns=("q", "s"), max_step=MAX_STEP)
        if not report.all_converged:
            raise ValueError(f"{model.name}: the legs do not close at the home pose {home.tolist()} for the design "
                             f"{ {k: round(v, 9) for k, v in values.items()} }, on the way from the start design")
        solution = report.solution
        assert isinstance(solution, dict), "solve_closure names its vectors"
        q, s = solution["q"], solution["s"]
    return q, s

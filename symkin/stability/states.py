"""States at which generated code is checked: random, along paths into singularities, scaled.

A *state* is a dict of input groups, each an array (count, size): ``q`` (and ``qd``,
``qdd``, ``tau``) for serial chains; for parallel mechanisms consistent task coordinates
``p`` and actuated joints ``q = ik(p)`` (the generated closed-form IK, the knee branch the
model declares), sampled around the model's ``home`` pose.  Groups a function takes that
are not listed here (a parallel mechanism's passive joint variables ``s``) are filled by
the harness.

Singular configurations are found generically by sweeping one coordinate at a time from a
random state and watching the inverse condition number 1/kappa = sigma_min/sigma_max of
the generated task Jacobian: the joints of a serial chain (each over a full turn or +-1 m),
the task coordinates of a parallel mechanism (positions over +-2 characteristic lengths,
angles over a full turn, q = ik(p) at every point; kappa of J^-1, which equals kappa of J).  Every local minimum below
:data:`CANDIDATE` - and, for a parallel mechanism, the last reachable point before the IK
fails (the workspace boundary, where the two knee branches merge and J loses rank) - is
refined by golden-section search to the floating-point floor and kept if 1/kappa falls
below :data:`SINGULAR`.  For the planar arm this finds theta2 = 0 and pi (stretched and
folded arm), for the UR10e the wrist (q5 = 0, pi), the elbow (q3 = 0, pi) and shoulder
singularities, for the DELTA its workspace boundary.  A path then approaches the singular
value x* from the side where the mechanism is assembled: x_j = x* +- t, t = 1e-1 ... 1e-12
(times the characteristic length for a platform position), so kappa grows like 1/t
(1/sqrt(t) at a boundary fold).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol
from dataclasses import dataclass

import numpy as np

from symkin.model import coordinates
from symkin.model.coordinates import coordinate_range
from symkin.model.schema import Model
from symkin.parallel.inputs import TASK_UNITS

#: Local minima of 1/kappa below this on the sweep grid are refined.
CANDIDATE = 2e-2
#: A refined minimum below this is a singular configuration.
SINGULAR = 1e-12
#: ... and, at a workspace boundary (a fold: 1/kappa ~ sqrt(distance)), below this.
SINGULAR_BOUNDARY = 1e-6
SWEEP_POINTS = 721
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
#: Parallel mechanisms: random platform positions lie within home +- this many characteristic
#: lengths, orientations within home +- ORIENTATION_SPREAD rad.
POSITION_SPREAD = 0.2
ORIENTATION_SPREAD = 0.2

States = dict[str, np.ndarray]
class IKSolution(Protocol):
    """What the generated closed-form IK of a parallel mechanism returns."""

    joints: np.ndarray
    margin: np.ndarray


#: The generated closed-form IK of a parallel mechanism: ik(p, **parameters) -> (.joints, .margin).
IK = Callable[..., IKSolution]


def length_parameters(model: Model) -> tuple[str, ...]:
    """Free parameters measured in metres: what a change of scale multiplies."""
    return tuple(p.name for p in model.parameters if p.unit.strip() == "m")


def parameter_values(model: Model, scale: float = 1.0) -> dict[str, float]:
    """Default parameter values as doubles, lengths multiplied by ``scale``."""
    lengths = set(length_parameters(model))
    return {p.name: float(p.value) * (scale if p.name in lengths else 1.0) for p in model.parameters}


def model_size(model: Model, scale: float = 1.0) -> float:
    """The largest length parameter (m) at ``scale``: the size of a parallel mechanism."""
    values = parameter_values(model, scale)
    return max((abs(values[name]) for name in length_parameters(model)), default=scale)


def _task_is_position(model: Model) -> np.ndarray:
    return np.array([TASK_UNITS[c] == "m" for c in model.task_space])


def scaled_home_pose(model: Model, scale: float = 1.0) -> np.ndarray:
    """The model's ``home`` task coordinates, positions multiplied by ``scale``."""
    assert model.parallel is not None
    if model.parallel.home is None:
        raise ValueError(f"model {model.name!r}: the stability harness samples around the platform's home pose; "
                         "declare parallel.home in the model file")
    home = np.array([float(v.xreplace(model.parameter_values)) for v in model.parallel.home])
    return np.where(_task_is_position(model), home * scale, home)


def assembled(ik: IK, p: np.ndarray, parameters: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """(q = ik(p), whether the mechanism assembles there: finite joints, every leg's margin >= 0)."""
    with np.errstate(invalid="ignore"):  # sqrt of a negative discriminant: unreachable, NaN
        result = ik(p, **parameters)
    q = np.asarray(result.joints, dtype=np.float64)
    margin = np.asarray(result.margin, dtype=np.float64)
    ok = np.all(np.isfinite(q), axis=-1) & np.all(margin >= 0, axis=-1)
    return q, ok


def _other_groups(model: Model, count: int, rng: np.random.Generator, states: States) -> States:
    for group in coordinates.GROUPS:
        if group != "q":
            states[group] = rng.uniform(-1.0, 1.0, size=(count, model.dof))
    return states


def random_states(model: Model, count: int, rng: np.random.Generator, *, scale: float = 1.0,
                  ik: IK | None = None) -> States:
    """``count`` random states; qd, qdd, tau uniform in [-1, 1].

    Serial: q uniform within the joint ranges (:func:`coordinate_range`).  Parallel (``ik``
    required): p uniform around :func:`scaled_home_pose` (+-POSITION_SPREAD characteristic lengths,
    +-ORIENTATION_SPREAD rad), kept where the mechanism assembles, q = ik(p).  ``scale``
    multiplies every length (parameters and positions).
    """
    if model.parallel is None:
        lower, upper = coordinate_range(model)
        return _other_groups(model, count, rng, {"q": rng.uniform(lower, upper, size=(count, model.dof))})
    if ik is None:
        raise ValueError("random states of a parallel mechanism need its generated ik")
    parameters = parameter_values(model, scale)
    spread = np.where(_task_is_position(model), POSITION_SPREAD * model_size(model, scale),
                      ORIENTATION_SPREAD)
    home = scaled_home_pose(model, scale)
    ps, qs = [], []
    for _attempt in range(50):
        p = home + rng.uniform(-1.0, 1.0, size=(2 * count, len(home))) * spread
        q, ok = assembled(ik, p, parameters)
        ps.append(p[ok])
        qs.append(q[ok])
        if sum(len(b) for b in ps) >= count:
            return _other_groups(model, count, rng, {"q": np.concatenate(qs)[:count], "p": np.concatenate(ps)[:count]})
    raise ValueError(f"model {model.name!r}: fewer than {count} of the poses sampled around home assemble; "
                     "is parallel.home inside the workspace?")


@dataclass(frozen=True)
class SingularPath:
    """A path x_j = value + side * t * unit into a singular configuration (other coordinates at ``base``).

    x is the joint vector q of a serial chain or the task coordinates p of a parallel
    mechanism; ``configure`` turns a batch of x into the states the generated code takes.
    """

    coordinate: int
    name: str
    value: float
    base: np.ndarray
    inverse_kappa: float
    configure: Callable[[np.ndarray], States]
    side: float = 1.0
    unit: float = 1.0

    @property
    def label(self) -> str:
        return f"{self.name} -> {self.value:.6g}"

    def states(self, ts: np.ndarray) -> States:
        x = np.tile(self.base, (len(ts), 1))
        x[:, self.coordinate] = self.value + self.side * self.unit * np.asarray(ts)
        return self.configure(x)


@dataclass(frozen=True)
class _Sweep:
    """What is swept: names, spans, which coordinates are angles, x -> states, and a start."""

    names: tuple[str, ...]
    spans: np.ndarray
    units: np.ndarray
    angular: np.ndarray
    configure: Callable[[np.ndarray], States]
    base: np.ndarray


def _serial_sweep(model: Model, rng: np.random.Generator) -> _Sweep:
    lower, upper = coordinate_range(model)
    revolute = np.array([j.turns for j in model.coordinates])
    return _Sweep(tuple(j.name for j in model.coordinates), np.where(revolute, np.pi, 1.0), np.ones(model.dof), revolute,
                  lambda q: {"q": q}, rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi)))


def _parallel_sweep(model: Model, rng: np.random.Generator, ik: IK) -> _Sweep:
    parameters = parameter_values(model)
    length = model_size(model)
    position = _task_is_position(model)

    def configure(p: np.ndarray) -> States:
        q, ok = assembled(ik, p, parameters)
        return {"q": np.where(ok[..., None], q, np.nan), "p": p}

    base = random_states(model, 1, rng, ik=ik)["p"][0]
    return _Sweep(tuple(model.task_space), np.where(position, 2 * length, np.pi), np.where(position, length, 1.0),
                  ~position, configure, base)


def _inverse_kappa(jacobian: Callable[..., np.ndarray], states: States) -> np.ndarray:
    """1/kappa of the task Jacobian (or its inverse) at a batch of states; +inf where the mechanism
    does not assemble, 0 where the generated matrix is not finite (a division by zero: singular)."""
    assembled_here = np.all(np.isfinite(states["q"]), axis=-1)
    safe = {g: np.where(assembled_here[..., None], v, 0.0) if g == "q" else v for g, v in states.items()}
    with np.errstate(divide="ignore", invalid="ignore"):
        J = np.asarray(jacobian(*safe.values()))
    finite = np.all(np.isfinite(J), axis=(-2, -1))
    s = np.linalg.svd(np.where(finite[..., None, None], J, 0.0), compute_uv=False)
    inverse_kappa = np.where(finite, s[..., -1] / np.where(s[..., 0] > 0, s[..., 0], 1.0), 0.0)
    return np.where(assembled_here, inverse_kappa, np.inf)


def _refine(f: Callable[[float], float], a: float, b: float) -> float:
    """Golden-section minimum of f on [a, b], down to the floating-point resolution of the arguments."""
    c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    while b - a > 4 * np.finfo(float).eps * max(1.0, abs(a), abs(b)):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN * (b - a)
            fd = f(d)
    return c if fc <= fd else d


def _snap(value: float) -> float:
    """A refined angle within 1e-12 of a multiple of pi/2 is that multiple (the singular values
    of the usual mechanisms: stretched, folded, aligned axes)."""
    multiple = round(value / (np.pi / 2))
    return multiple * (np.pi / 2) if abs(value - multiple * (np.pi / 2)) < 1e-12 else value


def _assembled_side(sweep: _Sweep, j: int, value: float, reach: float) -> float:
    """+1 or -1: the side of x_j = value along which the mechanism assembles for every t in
    [1e-12, reach] (+1 first; always +1 for a serial chain); 0 if neither."""
    ts = np.geomspace(1e-12, reach, 25)
    for side in (1.0, -1.0):
        x = np.tile(sweep.base, (len(ts), 1))
        x[:, j] = value + side * sweep.units[j] * ts
        if np.all(np.isfinite(sweep.configure(x)["q"])):
            return side
    return 0.0


def _distance(a: float, b: float, angular: bool) -> float:
    """|a - b|, for angles modulo 2 pi."""
    return abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi) if angular else abs(a - b)


def singular_paths(model: Model, jacobian: Callable[..., np.ndarray], rng: np.random.Generator,
                   limit: int = 8, per_coordinate: int = 2, ik: IK | None = None,
                   reach: float = 0.1) -> list[SingularPath]:
    """Paths into the singular configurations found by sweeping each coordinate (see module docstring).

    Args:
        model: the model.
        jacobian: the generated task Jacobian, vectorized over batches (``J(q)``, or ``J(q, p)``
            for a parallel mechanism).
        rng: random generator for the base configuration.
        limit: at most this many paths in all.
        per_coordinate: at most this many paths per swept coordinate (those nearest x_j = 0 first).
        ik: the generated IK (parallel mechanisms).
        reach: the largest step t a path takes (the mechanism must assemble up to it).
    """
    if model.parallel is not None and ik is None:
        raise ValueError(f"{model.name}: the singular paths of a parallel mechanism need its generated ik")
    sweep = _serial_sweep(model, rng) if ik is None or model.parallel is None else _parallel_sweep(model, rng, ik)
    found: list[SingularPath] = []
    for j, name in enumerate(sweep.names):
        centre = 0.0 if sweep.angular[j] else sweep.base[j]  # angles: a full turn around 0
        grid = centre + np.linspace(-sweep.spans[j], sweep.spans[j], SWEEP_POINTS)
        x = np.tile(sweep.base, (SWEEP_POINTS, 1))
        x[:, j] = grid
        r = _inverse_kappa(jacobian, sweep.configure(x))

        def at(value: float, j: int = j) -> float:
            point = sweep.base.copy()
            point[j] = value
            return float(_inverse_kappa(jacobian, sweep.configure(point[None]))[0])

        for i in range(SWEEP_POINTS):
            left, right = r[max(i - 1, 0)], r[min(i + 1, SWEEP_POINTS - 1)]
            edge = np.isfinite(r[i]) and not (np.isfinite(left) and np.isfinite(right))
            if not (r[i] <= left and r[i] <= right and (r[i] < CANDIDATE or edge)):
                continue
            value = _refine(at, grid[max(i - 1, 0)], grid[min(i + 1, SWEEP_POINTS - 1)])
            value = _snap(value) if sweep.angular[j] else value
            inverse_kappa = at(value)
            side = _assembled_side(sweep, j, value, reach)
            duplicate = any(p.coordinate == j and _distance(p.value, value, sweep.angular[j]) < 1e-9 * sweep.units[j]
                            for p in found)
            if side and inverse_kappa < (SINGULAR_BOUNDARY if edge else SINGULAR) and not duplicate:
                found.append(SingularPath(j, name, value, sweep.base, inverse_kappa, sweep.configure, side,
                                          float(sweep.units[j])))
    kept = []
    for j in range(len(sweep.names)):
        nearest_zero = sorted((p for p in found if p.coordinate == j), key=lambda p: abs(p.value))
        kept += sorted(nearest_zero[:per_coordinate], key=lambda p: p.value)
    return kept[:limit]

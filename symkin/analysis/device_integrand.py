"""The joint-space integrand of the global indices fused on JAX's default device (issue 66).

For a model loaded with the JAX backend, :func:`device_joint_space_integrand` gives the integrand of
:func:`symkin.analysis.global_indices.joint_space_integrand` - components [w g, w] with w = |det J(q)| (the
Cartesian measure) or 1 (the joint measure) and g = 1/kappa = sigma_min / sigma_max of the (homogenized) Jacobian
(seed eqs. 8.25, 8.28), or [w] for the workspace measure - as one jitted function: the generated Jacobian, its
extreme singular values (conditioning's closed forms for 2 x 2 and 3 x 3, else one-sided Jacobi), the weights and
the reduction of a batch to its mean and scatter run on the device,
and only those k + k^2 numbers come back (:attr:`symkin.integration.integrand.Integrand.moments`).  On a GPU a
batch of configurations never leaves the device; on a CPU XLA fuses the program.  The program is compiled once per
generated Jacobian: the model's parameters are its arguments (traced), so every design of a sweep
(:mod:`symkin.design.sweep_metrics`) runs the same compiled code.  The rules are
:mod:`symkin.numerics.conditioning`'s: singular values at most max(m, n) eps sigma_max count as 0, a Jacobian
with a non-finite entry has 1/kappa = 0.

:func:`device_torque_peak` reduces the sweeps' peak effort per unit TCP force (the largest column norm of J's
position rows over the configurations that count) on the device the same way.

The configurations that count are the host's (:func:`symkin.mechanism.working_mode.jacobian_in_working_mode`),
decided on the device too: those within the model's joint stops (:mod:`symkin.mechanism.stops`, their rows passed
as arguments) and, for a parallel mechanism with closed forms, those in its working mode - fk(q) assembles and
ik(fk(q)) = q (:func:`symkin.mechanism.working_mode.same_branches`, the host's test in jax.numpy), the Jacobian
J(q, fk(q)).  A parallel mechanism with declared passive-joint limits (checked on the closure, on the
host), legs without closed forms, and an index other than 1/kappa take the host integrand.  The singular values
call no LAPACK kernel (:mod:`symkin.numerics.jacobi_svd`), so |det J| is the program's only one (run concurrently,
jaxlib's CPU LAPACK kernels deadlock on a 2-core machine: :mod:`symkin.numerics.ordered_linalg`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from symkin import mechanism
from symkin.integration.integrand import Integrand
from symkin.mechanism import Limits, reach, stops, working_mode
from symkin.numerics import conditioning, jacobi_svd
from symkin.numerics.ordered_linalg import InOrder
from symkin.runtime.info import GeneratedModel

_EPS = float(np.finfo(np.float64).eps)


def loaded_with_jax(model: GeneratedModel) -> bool:
    """Whether the model is loaded with the JAX backend, its generated functions traceable unbound (``unbound``)."""
    return getattr(model, "backend", None) == "jax" and hasattr(model, "unbound")


def on_device(model: GeneratedModel) -> bool:
    """Whether the model's joint-space integrand can run fused on JAX's device: a model loaded with the JAX backend
    whose working mode its generated functions decide (:func:`symkin.mechanism.working_mode.assembly_functions`:
    an open chain, or loops closed through closed-form fk and ik without passive-joint limits)."""
    return loaded_with_jax(model) and working_mode.assembly_functions(model) is not None


def jacobian_of_joints_on_device(model: GeneratedModel) -> bool:
    """Whether the model is loaded with JAX and its task Jacobian is J(q) at every configuration (an open chain: the
    smooth surrogate's gradient and the design optimizer's JAX path take it)."""
    return on_device(model) and working_mode.assembly_functions(model) == ()


def row_scale(model: GeneratedModel, box: np.ndarray, length: float | str | None) -> np.ndarray:
    """1/L on the translational rows of a task space that mixes lengths and angles, else 1
    (:func:`symkin.numerics.conditioning.homogenize`)."""
    rows = len(mechanism.task_space(model))
    L = reach.homogenizing_length(model, length, box)
    return np.ones(rows) if L is None else conditioning.homogenizing_scale(rows, L, mechanism.position_rows(model))


class _Functions(NamedTuple):
    """The generated functions the device program calls (hashable: the compile cache's key): the Jacobian, and for a
    mechanism that closes loops its closed-form fk and ik (None for an open chain)."""

    jacobian: Callable[..., Any]
    fk: Callable[..., Any] | None = None
    ik: Callable[..., Any] | None = None


#: At most this share of a batch of 3 x 3 Jacobians takes a batched SVD of its own where the closed form does not serve
#: them (:func:`symkin.numerics.conditioning.closed_form_3x3`'s ``hard`` ones); a batch with more takes one of all.
HARD_SHARE = 1 / 16


def on_gathered_rows(mask: Any, shares: tuple[float, ...], function: Callable[..., Any], *arrays: Any) -> Any:
    """``function(*rows)`` - an array (k,) or a tuple of them - at the rows of ``arrays`` where ``mask`` (N,) holds,
    0 elsewhere, in jax.numpy: evaluated on the masked rows gathered to s N rows for the first share s in ``shares``
    that holds them all, or on every row where none does (a jax.lax.cond per share chooses; only the branch taken
    runs)."""
    import jax
    import jax.numpy as jnp

    count = mask.shape[0]
    if not shares:
        return jax.tree_util.tree_map(lambda v: jnp.where(mask, v, 0.0), function(*arrays))
    size = max(1, int(count * shares[0]))

    def gathered(_: Any) -> Any:
        rows = jnp.nonzero(mask, size=size, fill_value=0)[0]   # the fill repeats row 0: it scatters row 0's own value
        return jax.tree_util.tree_map(lambda v: jnp.zeros(count, v.dtype).at[rows].set(jnp.where(mask[rows], v, 0.0)),
                                      function(*(a[rows] for a in arrays)))

    def wider(_: Any) -> Any:
        return on_gathered_rows(mask, shares[1:], function, *arrays)

    return jax.lax.cond(jnp.sum(mask) > size, wider, gathered, None)


def extreme_singular_values(J: Any, threshold: float) -> tuple[Any, Any]:
    """(sigma_max, sigma_min) of a batch of finite Jacobians (N, m, n) in jax.numpy by
    :mod:`symkin.numerics.conditioning`'s rules: its closed forms for 2 x 2 and 3 x 3 matrices (the host's formulas,
    several times faster than a batched SVD), the singular values by one-sided Jacobi otherwise
    (:func:`symkin.numerics.jacobi_svd.jacobi_singular_values`: no LAPACK kernel; XLA's SVD took twice as long) and
    for the 3 x 3 matrices the closed form does not serve - gathered to a static share of the batch (:data:`HARD_SHARE`;
    more take the sweeps over the whole batch); a sigma_min at most ``threshold`` sigma_max is 0 (the numerical
    rank)."""
    import jax.numpy as jnp

    def extremes(A: Any) -> tuple[Any, Any]:
        s = jacobi_svd.jacobi_singular_values(A)
        return jnp.max(s, axis=-1), jnp.min(s, axis=-1)

    m, n = J.shape[-2:]
    if m == n == 2:
        largest, smallest = conditioning.extreme_2x2(J, jnp)
    elif m == n == 3:
        largest, smallest, hard = conditioning.closed_form_3x3(J, jnp)
        exact_largest, exact_smallest = on_gathered_rows(hard, (HARD_SHARE,), extremes, J)
        largest, smallest = jnp.where(hard, exact_largest, largest), jnp.where(hard, exact_smallest, smallest)
    else:
        largest, smallest = extremes(J)
    return largest, jnp.where(smallest <= threshold * largest, 0.0, smallest)


def _jacobian_and_inside(functions: _Functions, q: Any, joint_stops: Any, revolute: Any, parameters: dict[str, Any]
                         ) -> tuple[Any, Any]:
    """The task Jacobian at configurations q (N, n) and the configurations that count (N,), in jax.numpy: within
    the joint stops and, where the model closes loops, in the working mode (:mod:`symkin.mechanism.working_mode`:
    fk assembles and ik(fk(q)) = q; J(q, fk(q)))."""
    import jax.numpy as jnp

    rows, offsets, lower, upper = joint_stops
    inside = stops.within_stops(q, rows, offsets, lower, upper, xp=jnp)
    if functions.fk is None or functions.ik is None:
        return functions.jacobian(q, **parameters["jacobian"]), inside
    p = functions.fk(q, **parameters["fk"]).position
    assembled = jnp.where(jnp.isfinite(p), p, 0.0)
    back = functions.ik(assembled, **parameters["ik"]).joints
    inside = inside & working_mode.same_branches(q, p, back, revolute, jnp)
    return functions.jacobian(q, assembled, **parameters["jacobian"]), inside


@functools.lru_cache(maxsize=32)
def _compiled(functions: _Functions, measure: str, with_index: bool, threshold: float) -> tuple[Any, Any]:
    """(values, reduce) jitted once per generated function set and options: the parameters, the rows' scale, the
    joint stops and the revolute mask are arguments, traced, so that every design of a sweep runs the same compiled
    program.  reduce gives (mean, scatter, lowest, highest): the moments of the values and the extremes of 1/kappa
    where w > 0."""
    import jax
    import jax.numpy as jnp

    def values(q: Any, scale: Any, joint_stops: Any, revolute: Any, parameters: dict[str, Any]) -> tuple[Any, Any]:
        J, inside = _jacobian_and_inside(functions, q, joint_stops, revolute, parameters)
        finite = jnp.all(jnp.isfinite(J), axis=(-2, -1))
        J = jnp.where(finite[:, None, None], J, 0.0)
        weight = jnp.abs(jnp.linalg.det(J)) if measure == "cartesian" else jnp.ones(q.shape[0])
        weight = jnp.where(inside, weight, 0.0)
        if not with_index:
            return weight[:, None], weight
        largest, smallest = extreme_singular_values(J * scale[:, None], threshold)
        index = jnp.where(finite & (largest > 0), smallest / jnp.where(largest > 0, largest, 1.0), 0.0)
        return jnp.stack([weight * index, weight], axis=-1), index

    def reduce(q: Any, scale: Any, joint_stops: Any, revolute: Any, parameters: dict[str, Any]
               ) -> tuple[Any, Any, Any, Any]:
        return reduced(*values(q, scale, joint_stops, revolute, parameters))

    return jax.jit(lambda *arguments: values(*arguments)[0]), jax.jit(reduce)


def reduced(f: Any, index: Any) -> tuple[Any, Any, Any, Any]:
    """(mean, scatter, lowest, highest) of a batch's values f (N, k), on the device: the moments
    :attr:`symkin.integration.integrand.Integrand.moments` gives back, and the extremes of ``index`` (N,) where
    the last component (the measure) is positive, inf and -inf where it is nowhere."""
    import jax.numpy as jnp

    mean = f.mean(axis=0)
    centered = f - mean
    inside = f[:, -1] > 0
    return (mean, centered.T @ centered, jnp.min(jnp.where(inside, index, jnp.inf)),
            jnp.max(jnp.where(inside, index, -jnp.inf)))


def stop_arguments(model: GeneratedModel) -> tuple[Any, ...]:
    """The model's joint stops (:class:`symkin.mechanism.stops.StopInequalities`) as the device programs take them:
    (rows, offsets, lower, upper) in jax.numpy, for :func:`symkin.mechanism.stops.within_stops`."""
    import jax.numpy as jnp

    n = len(mechanism.coordinate_names(model))
    joint_stops = stops.StopInequalities.of_model(model)
    return tuple(jnp.asarray(a, dtype=jnp.float64) for a in (joint_stops.rows.reshape(-1, n), joint_stops.offsets,
                                                             joint_stops.lower, joint_stops.upper))


def device_joint_space_integrand(model: GeneratedModel, *, with_index: bool = True, measure: str = "cartesian",
                                 limits: Limits | None = None, length: float | str | None = None,
                                 extremes: Callable[[float, float], None] | None = None) -> Integrand:
    """The joint-space integrand [w 1/kappa, w] (``with_index``) or [w] of a model loaded with the JAX backend
    (:func:`on_device`), its batches reduced on the device (see the module docstring).  ``extremes``: called with the
    smallest and largest 1/kappa of each batch's points inside the workspace (w > 0; inf and -inf where none is)."""
    import jax.numpy as jnp

    box = mechanism.joint_limits(model, limits)
    m, n = len(mechanism.task_space(model)), box.shape[0]
    if measure == "cartesian" and m != n:
        raise ValueError(f"{model.name}: the Cartesian measure |det J| dq needs a square task Jacobian, "
                         f"this one is {m} x {n}; use measure='joint' or the Cartesian domain")
    scale = jnp.asarray(row_scale(model, box, length) if with_index else np.ones(m))
    functions, model_arguments = _program_of(model)
    evaluate, reduce = _compiled(functions, measure, with_index, max(m, n) * _EPS)
    arguments = (scale, *model_arguments)

    def moments(q: np.ndarray) -> tuple[Any, Any]:
        mean, scatter, lowest, highest = reduce(jnp.asarray(q), *arguments)
        if extremes is not None:
            extremes(float(lowest), float(highest))
        return mean, scatter

    components = ("index dW", "dW") if with_index else ("dW",)
    return Integrand(box[:, 0], box[:, 1], lambda q: np.asarray(evaluate(jnp.asarray(q), *arguments)),
                     components, mechanism.coordinate_names(model), moments=moments)


def _program_of(model: GeneratedModel) -> tuple[_Functions, tuple[Any, Any, dict[str, dict[str, Any]]]]:
    """The generated functions a device program of ``model`` calls (:class:`_Functions`: the compile cache's key) and
    the model's arguments to it: its joint stops (:func:`stop_arguments`), revolute mask and the functions'
    parameters."""
    import jax.numpy as jnp

    names = ("jacobian", *(working_mode.assembly_functions(model) or ()))
    unbound = {name: model.unbound(name) for name in names}
    parameters = {name: values for name, (_, values) in unbound.items()}
    return (_Functions(*(function for function, _ in unbound.values())),
            (stop_arguments(model), jnp.asarray(mechanism.revolute_mask(model)), parameters))


@functools.lru_cache(maxsize=32)
def _compiled_levers(functions: _Functions, position_rows: tuple[int, ...]) -> Any:
    """``levers(q, joint_stops, revolute, parameters) -> (max_q max_i ||J_p[:, i](q)||, the count of configurations
    that count)`` over the configurations that count with a finite J_p, jitted once per generated function set."""
    import jax
    import jax.numpy as jnp

    def levers(q: Any, joint_stops: Any, revolute: Any, parameters: dict[str, Any]) -> tuple[Any, Any]:
        J, inside = _jacobian_and_inside(functions, q, joint_stops, revolute, parameters)
        position = J[:, list(position_rows), :]
        norms = jnp.sqrt(jnp.sum(position * position, axis=1))          # (N, n): ||J_p[:, i]||
        counted = inside & jnp.all(jnp.isfinite(norms), axis=1)
        return jnp.max(jnp.where(counted[:, None], norms, -jnp.inf)), jnp.sum(counted)

    return jax.jit(levers)


def device_torque_peak(model: GeneratedModel, q: np.ndarray) -> float:
    """The largest column norm of the position rows J_p of the task Jacobian over the configurations q (N, n) that
    count (:func:`on_device`'s model: within the joint stops, a parallel mechanism's in its working mode) - the peak
    effort per unit TCP force of :func:`symkin.design.sweep_metrics.torque_peak` - reduced on JAX's device: only the
    number comes back.  ValueError where no configuration counts."""
    import jax.numpy as jnp

    functions, arguments = _program_of(model)
    peak, count = _compiled_levers(functions, tuple(mechanism.position_rows(model)))(jnp.asarray(q), *arguments)
    if int(count) == 0:
        raise ValueError("no configuration of the working mode among the sampled ones")
    return float(peak)


def smooth_gci_gradient(model: GeneratedModel, points: np.ndarray, *, measure: str = "cartesian",
                        length: float | None = None) -> tuple[float, dict[str, float]]:
    """The smooth surrogate of the GCI over fixed configurations and its gradient with respect to the model's free
    parameters, by ``jax.value_and_grad`` through the generated Jacobian (reverse mode): a design optimizer's objective
    and gradient (issue 66, "gradients for design").

        v(p) = sum_i w_i g_i / sum_i w_i,   g = 1/kappa_F = k / sqrt(||J||_F^2 trace((J^T J)^-1)),

    w = |det J| (``measure="cartesian"``) or 1, J the (homogenized) task Jacobian at ``points`` (N, n) with the
    parameters p - the Monte Carlo estimate of the GCI with the Frobenius condition number, which has no kink where
    singular values cross (:func:`symkin.numerics.conditioning.inverse_frobenius_condition_number`, Gosselin and
    Angeles 1991).  The points stay fixed as the parameters move (sample the joint limits once, e.g. a Sobol set), so
    the gradient is that of a smooth function; ``length`` homogenizes a mixed task space and is held fixed.
    Configurations with a singular J^T J give NaN: keep the points off the singularities (or use the joint measure
    with limits that avoid them).

    Returns:
        (v, {parameter: dv/dparameter}) for every free parameter the generated Jacobian takes.
    """
    import jax.numpy as jnp

    if not jacobian_of_joints_on_device(model):
        raise ValueError(f"{model.name}: the smooth GCI's gradient needs a serial model loaded with the JAX backend "
                         "(symkin.load(directory, backend='jax'))")
    m = len(mechanism.task_space(model))
    scale = jnp.asarray(row_scale(model, mechanism.joint_limits(model), length))
    if measure == "cartesian" and m != np.shape(points)[-1]:
        raise ValueError(f"{model.name}: the Cartesian measure |det J| dq needs a square task Jacobian; use "
                         "measure='joint'")
    jacobian, parameters = model.unbound("jacobian")
    value, gradient = compiled_surrogate_gradient(jacobian, measure)(jnp.asarray(points, dtype=jnp.float64), scale, parameters)
    return float(value), {name: float(g) for name, g in gradient.items()}


def inverse_frobenius(J: Any, xp: Any) -> Any:
    """1/kappa_F = n / (||J||_F ||J^-1||_F) of square Jacobians (N, n, n) in the array module ``xp`` (jax.numpy, or
    a device program's :class:`symkin.numerics.ordered_linalg.InOrder`), ||J^-1||_F^2 = trace((J^T J)^-1): NaN where
    J^T J is exactly singular."""
    inverse_sum = xp.trace(xp.linalg.inv(xp.swapaxes(J, -1, -2) @ J), axis1=-2, axis2=-1)
    return J.shape[-1] / xp.sqrt(xp.sum(J * J, axis=(-2, -1)) * inverse_sum)


@functools.lru_cache(maxsize=32)
def compiled_surrogate_gradient(jacobian: Callable[..., Any], measure: str, objective: str = "gci",
                                smoothing: float = 0.0) -> Any:
    """jax.value_and_grad of a smooth design surrogate by the parameters, jitted once per generated Jacobian and
    options (points, scale and parameters traced: an optimizer's later calls reuse it).  Called as
    ``f(points, scale, parameters) -> (value, {name: derivative})``.

    ``objective="gci"``: sum_i w_i g_i / sum_i w~_i (see :func:`smooth_gci_gradient`); ``"workspace"``: sum_i w~_i
    (times the volume per node, the Monte Carlo estimate of int |det J| dq).  w~ = sqrt(w^2 + smoothing^2 mean w^2)
    smooths the kink of |det J| where a node's det J changes sign as the design varies
    (:data:`symkin.design.formulation.DETERMINANT_SMOOTHING`; 0: w~ = w)."""
    import jax
    import jax.numpy as jnp

    def surrogate(q: Any, scale: Any, parameters: dict[str, Any]) -> Any:
        raw = jacobian(q, **parameters)
        xp = InOrder(jnp)  # det and inv one after the other (see symkin.numerics.ordered_linalg)
        weight = jnp.abs(xp.linalg.det(raw)) if measure == "cartesian" else jnp.ones(q.shape[0])
        smoothed = weight if smoothing == 0 else jnp.sqrt(weight * weight + smoothing**2 * jnp.mean(weight * weight))
        if objective == "workspace":
            return jnp.sum(smoothed)
        return jnp.sum(weight * inverse_frobenius(raw * scale[:, None], xp)) / jnp.sum(smoothed)

    return jax.jit(jax.value_and_grad(surrogate, argnums=2))

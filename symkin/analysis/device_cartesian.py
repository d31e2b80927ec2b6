"""The Cartesian-domain integrand of the global indices fused on JAX's default device (issue 66).

For a parallel mechanism with closed-form inverse kinematics loaded with the JAX backend,
:func:`device_cartesian_integrand` gives the integrand of :func:`symkin.analysis.global_indices.cartesian_integrand`
over a box of TCP points - components [1_W g, 1_W], or [1_W] for the workspace measure, with 1_W the reachability
indicator and g = 1/kappa of the (homogenized) task Jacobian there (seed eqs. 8.25, 8.29) - as one jitted function
whose batches are reduced to their mean and scatter on the device (:func:`symkin.analysis.device_integrand.reduced`):
on a GPU the points' joints and Jacobians never leave it; with ``extremes`` (a sweep's kappa extremes,
:mod:`symkin.design.sweep_metrics`) the smallest and largest 1/kappa of each batch's reachable points come back
with its moments.  The program is compiled once per set of generated functions; the parameters, limits, stops and
the held orientation are its arguments, traced.

A point counts as the host's rules count it (:mod:`symkin.mechanism.reach`, :mod:`symkin.mechanism.feasibility`):

* every leg reaches it: the generated ``ik`` is finite;
* it is in the working mode: for a translational platform (the DELTA) fk(ik(p)) returns to p within
  :data:`~symkin.mechanism.reach.POSITION_ROUND_TRIP_TOLERANCE` times the mechanism's size
  (:class:`~symkin.mechanism.reach.WorkingModeInverse`); for a pose platform held at a constant orientation
  (Stewart-Gough), det J^-1 has the sign it has at the home pose
  (:class:`~symkin.mechanism.reach.ConstantOrientationInverse`);
* the actuators are within their limits, angles wrapped into them (:func:`symkin.mechanism.limits.within_limits`),
  and within the joint stops.

The Jacobian is taken at the wrapped joints, as the host takes it, and only at the reachable points, gathered
(:func:`symkin.analysis.device_integrand.on_gathered_rows`: a box around the workspace holds many points out of
reach). For a translational platform it is the generated ``jacobian`` J(q, p); a platform held at a constant
orientation has the twist Jacobian J = R (J^-1)^-1 (R = diag(I, E),
:class:`~symkin.mechanism.reach.ConstantOrientation`), homogenized S J, whose 1/kappa is that of its inverse
J^-1 (S R)^-1 - one constant matrix for the batch, so no inverse per point (the host inverts,
:func:`symkin.numerics.conditioning.from_inverse`: the same index up to rounding, the numerical-rank rule applied to
the inverse's singular values). Declared passive-joint limits (decided on the loop closure by a Gauss-Newton iteration
on the host) take the host integrand.

A serial arm's closed form (:class:`symkin.analysis.inverse.ClosedFormInverse`) runs on the device where its solver
traces in jax.numpy (:data:`TRACEABLE_SOLVERS`: the planar 2R of the seed's Fig. 8.19, both elbow branches by the
half-angle law of cosines): the host's rules point by point - a branch is valid where it exists and the generated fk
reproduces the target within :data:`symkin.ik.closed_form.VALID_TOLERANCE` of max(1, |target|), each point takes its
first valid branch within the limits (angles wrapped into them) and the stops, and 1/kappa is that of the
(homogenized) task Jacobian J(q) there.

A spherical platform's orientation workspace (:mod:`symkin.analysis.orientations`: the roll-pitch-yaw box, the
invariant measure |cos pitch|) runs on the device by :func:`device_orientation_integrand` with the host's rules: an
orientation is reachable where the generated ``ik`` is finite and its joints are within the limits (angles wrapped
into them) and the stops, and 1/kappa is that of J^-1 E^-1 (E the angular-velocity matrix, inverted by cofactors:
:mod:`symkin.numerics.cofactors`), at the reachable orientations gathered (the Agile Eye reaches 9 % of the chart).

The singular values are one-sided Jacobi's (:mod:`symkin.numerics.jacobi_svd`), so det J^-1 is the one
LAPACK kernel of the program (jaxlib's CPU LAPACK kernels deadlock when run side by side:
:mod:`symkin.numerics.ordered_linalg`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from symkin import mechanism
from symkin.analysis.device_integrand import (extreme_singular_values, loaded_with_jax, on_gathered_rows, reduced,
                                             row_scale, stop_arguments)
from symkin.analysis.inverse import ClosedFormInverse
from symkin.ik.closed_form import UNREACHABLE, VALID_TOLERANCE
from symkin.ik.planar import Planar2R
from symkin.integration.integrand import Integrand
from symkin.mechanism import Limits, stops
from symkin.mechanism.feasibility import InverseKinematics
from symkin.mechanism.limits import within_limits
from symkin.mechanism.reach import (POSITION_ROUND_TRIP_TOLERANCE, ConstantOrientationInverse, WorkingModeInverse,
                                    angular_velocity_matrix)
from symkin.numerics import cofactors
from symkin.runtime.info import GeneratedModel

_EPS = float(np.finfo(np.float64).eps)
#: The serial closed forms whose ``candidates`` take an array module (jax.numpy traces them).
TRACEABLE_SOLVERS = (Planar2R,)


def cartesian_on_device(model: GeneratedModel, inverse: InverseKinematics) -> bool:
    """Whether the Cartesian integrand of ``model`` with ``inverse`` can run fused on JAX's device: a model loaded with
    the JAX backend whose inverse is its generated closed form (a translational platform's, or a pose platform's held
    at a constant orientation) without declared passive-joint limits, or a serial arm's closed form that traces in
    jax.numpy (:func:`traced_closed_form_on_device`)."""
    if isinstance(inverse, ClosedFormInverse):
        return traced_closed_form_on_device(model, inverse)
    return (loaded_with_jax(model) and isinstance(inverse, (WorkingModeInverse, ConstantOrientationInverse))
            and inverse.passive_limits is None)


def traced_closed_form_on_device(model: GeneratedModel, inverse: ClosedFormInverse) -> bool:
    """Whether a serial arm's closed-form inverse runs on JAX's device: the model is loaded with the JAX backend, the
    solver's candidates take an array module (:class:`symkin.ik.planar.Planar2R`: the half-angle law of cosines and
    subproblem 1 in jax.numpy) and its residual is the generated ``fk``'s TCP position (no generated
    ``task_coordinates``)."""
    return (loaded_with_jax(model) and isinstance(inverse.solver.solver, TRACEABLE_SOLVERS)
            and inverse.solver.kind == "task" and "task_coordinates" not in model.functions)


class _Functions(NamedTuple):
    """The generated functions the program calls (hashable: the compile cache's key): ik, and fk with the
    ``jacobian`` of a translational platform, or the ``inverse_jacobian`` of a platform held at an orientation."""

    ik: Callable[..., Any]
    fk: Callable[..., Any] | None
    jacobian: Callable[..., Any] | None
    inverse_jacobian: Callable[..., Any] | None


#: The reachable points' Jacobians and 1/kappa are evaluated on the reachable points gathered to the first of these
#: shares of a batch that holds them all (a box around the workspace holds many points out of reach: 88 % of the
#: Stewart platform's, 70 % of the DELTA's), or on every point of a batch where more are reachable.
REACHABLE_SHARES = (1 / 8, 1 / 2)


@functools.lru_cache(maxsize=32)
def _compiled(functions: _Functions, with_index: bool, threshold: float, wraps: bool) -> tuple[Any, Any]:
    """(values, reduce) jitted once per generated function set and options (see the module docstring); ``wraps``:
    some actuator is an angle, so the Jacobian is evaluated again at the joints wrapped into their limits."""
    import jax
    import jax.numpy as jnp

    def inverse_condition(q: Any, points: Any, poses: Any, constants: dict[str, Any], parameters: dict[str, Any]
                          ) -> Any:
        """1/kappa of the homogenized task Jacobian S J at the points (0 where it is singular or not finite).  A
        platform held at an orientation has J = R (J^-1)^-1 (R = diag(I, E)), whose singular values are the
        reciprocals of those of (S J)^-1 = J^-1 (S R)^-1: its 1/kappa needs no inverse per point."""
        if functions.jacobian is not None:
            J = functions.jacobian(q, points, **parameters["jacobian"]) * constants["scale"][:, None]
        else:
            assert functions.inverse_jacobian is not None, "a platform held at an orientation: its J^-1"
            J = functions.inverse_jacobian(q, poses, **parameters["inverse_jacobian"]) @ constants["unscale"]
        return _device_inverse_condition(J, threshold)

    def values(points: Any, constants: dict[str, Any], parameters: dict[str, Any]) -> tuple[Any, Any]:
        held = constants["orientation"]
        poses = points if held is None else jnp.concatenate([points, jnp.broadcast_to(held, points.shape)], axis=-1)
        q = functions.ik(poses, **parameters["ik"]).joints
        finite = jnp.all(jnp.isfinite(q), axis=-1)
        q = jnp.where(finite[:, None], q, 0.0)
        if functions.fk is not None:  # fk(ik(p)) returns to p: the fk branch of the working mode
            back = functions.fk(q, **parameters["fk"]).position
            in_mode = jnp.all(jnp.abs(back - points) <= constants["tolerance"], axis=-1)
        else:  # det J^-1 keeps the sign of the home pose's: its assembly mode
            assert functions.inverse_jacobian is not None, "a platform held at an orientation: its J^-1"
            J_inverse = functions.inverse_jacobian(q, poses, **parameters["inverse_jacobian"])
            in_mode = constants["sign"] * jnp.linalg.det(J_inverse) > 0
        wrapped, inside = within_limits(q, constants["limits"], constants["revolute"], xp=jnp)
        rows, offsets, lower, upper = constants["stops"]
        reachable = finite & in_mode & inside & stops.within_stops(wrapped, rows, offsets, lower, upper, xp=jnp)
        indicator = reachable.astype(jnp.float64)
        if not with_index:
            return indicator[:, None], indicator
        # after det (the cond waits for reachable): the factorizations still run one at a time
        index = on_gathered_rows(reachable, REACHABLE_SHARES,
                                 lambda joints, centres, held_poses: inverse_condition(joints, centres, held_poses,
                                                                                       constants, parameters),
                                 wrapped if wraps else q, points, poses)
        return jnp.stack([index, indicator], axis=-1), index

    return (jax.jit(lambda *arguments: values(*arguments)[0]),
            jax.jit(lambda *arguments: reduced(*values(*arguments))))


@functools.lru_cache(maxsize=32)
def _compiled_traced_closed_form(solver: Any, order: tuple[int, ...], rows: tuple[int, ...], fk: Callable[..., Any],
                                 jacobian: Callable[..., Any], with_index: bool, threshold: float) -> tuple[Any, Any]:
    """(values, reduce) of a serial arm's closed form (:func:`traced_closed_form_on_device`), jitted once per solver,
    generated functions and options: :meth:`symkin.ik.closed_form.ClosedFormIK.solve` without shifts (the branches
    valid where they exist and fk reproduces the target within VALID_TOLERANCE of max(1, |target|)), then
    :func:`symkin.mechanism.feasibility.feasible_configurations` (each point's first branch within the limits and the
    stops, its angles wrapped into them) and 1/kappa of the (scaled) Jacobian there."""
    import jax
    import jax.numpy as jnp

    def values(points: Any, constants: dict[str, Any], parameters: dict[str, Any]) -> tuple[Any, Any]:
        target = points[:, list(order)]
        q, flags = solver.candidates(target, xp=jnp)                       # (N, B, n), (N, B)
        count, branches, n = q.shape
        exists = jnp.all(jnp.isfinite(q), axis=-1) & ((flags & int(UNREACHABLE)) == 0)
        at = jnp.where(jnp.isfinite(q), q, 0.0).reshape(-1, n)
        reached = fk(at, **parameters["fk"])[:, list(rows), 3].reshape(count, branches, len(rows))
        error = jnp.linalg.norm(target[:, None, :] - reached, axis=-1)
        scale = jnp.maximum(1.0, jnp.linalg.norm(target, axis=-1))[:, None]
        valid = exists & (error <= VALID_TOLERANCE * scale)
        wrapped, inside = within_limits(q, constants["limits"], constants["revolute"], xp=jnp)
        row_stops, offsets, lower, upper = constants["stops"]
        feasible = valid & inside & stops.within_stops(wrapped, row_stops, offsets, lower, upper, xp=jnp)
        first = jnp.argmax(feasible, axis=1)
        chosen = jnp.take_along_axis(wrapped, first[:, None, None], axis=1)[:, 0]
        reachable = jnp.any(feasible, axis=1)
        indicator = reachable.astype(jnp.float64)
        if not with_index:
            return indicator[:, None], indicator
        J = jacobian(jnp.where(reachable[:, None], chosen, 0.0), **parameters["jacobian"]) * constants["scale"][:, None]
        index = jnp.where(reachable, _device_inverse_condition(J, threshold), 0.0)
        return jnp.stack([index, indicator], axis=-1), index

    return (jax.jit(lambda *arguments: values(*arguments)[0]),
            jax.jit(lambda *arguments: reduced(*values(*arguments))))


def _device_inverse_condition(J: Any, threshold: float) -> Any:
    """1/kappa = sigma_min / sigma_max of a batch of Jacobians (N, m, n) in jax.numpy - the device's
    :func:`symkin.numerics.conditioning.inverse_condition_number`, by
    :func:`symkin.analysis.device_integrand.extreme_singular_values` - 0 where J has a non-finite entry or vanishes."""
    import jax.numpy as jnp

    regular = jnp.all(jnp.isfinite(J), axis=(-2, -1))
    largest, smallest = extreme_singular_values(jnp.where(regular[:, None, None], J, 0.0), threshold)
    return jnp.where(regular & (largest > 0), smallest / jnp.where(largest > 0, largest, 1.0), 0.0)


def _integrand(model: GeneratedModel, lower: np.ndarray, upper: np.ndarray, evaluate: Any, reduce: Any,
               constants: dict[str, Any], parameters: dict[str, Any], with_index: bool,
               axes: tuple[str, ...] | None = None,
               extremes: Callable[[float, float], None] | None = None) -> Integrand:
    """The Integrand over the box [lower, upper] whose values are ``evaluate``'s and whose batches ``reduce`` reduces
    to their moments on the device (both called with the points, ``constants`` and ``parameters``); ``axes``: the
    box's coordinates (default: the model's position axes); ``extremes``: called with the smallest and largest
    1/kappa of each batch's points inside the workspace (inf and -inf where none is), as the moments come back."""
    import jax.numpy as jnp

    def moments(points: np.ndarray) -> tuple[Any, Any]:
        mean, scatter, lowest, highest = reduce(jnp.asarray(points), constants, parameters)
        if extremes is not None:
            extremes(float(lowest), float(highest))
        return mean, scatter

    axes = axes or tuple("xyz"[a] for a in mechanism.position_axes(model))
    components = ("index dW", "dW") if with_index else ("dW",)
    return Integrand(lower, upper, lambda points: np.asarray(evaluate(jnp.asarray(points), constants, parameters)),
                     components, axes, indicator=len(components) - 1, moments=moments)


def _traced_closed_form_integrand(model: GeneratedModel, inverse: ClosedFormInverse, lower: np.ndarray,
                                  upper: np.ndarray, joint_box: np.ndarray, scale: np.ndarray,
                                  with_index: bool, extremes: Callable[[float, float], None] | None) -> Integrand:
    """:func:`device_cartesian_integrand` of a serial arm's closed form (:func:`traced_closed_form_on_device`)."""
    import jax.numpy as jnp

    m, n = len(mechanism.task_space(model)), joint_box.shape[0]
    rows = tuple(mechanism.POSITION_COMPONENTS.index(c) for c in mechanism.task_space(model))
    (fk, fk_values), (jacobian, jacobian_values) = model.unbound("fk"), model.unbound("jacobian")
    constants = {"limits": jnp.asarray(joint_box), "revolute": jnp.asarray(mechanism.revolute_mask(model)),
                 "stops": stop_arguments(model), "scale": jnp.asarray(scale)}
    parameters = {"fk": fk_values, "jacobian": jacobian_values}
    solver: Any = inverse.solver.solver  # a TRACEABLE_SOLVERS instance: hashable by identity (the compile cache's key)
    evaluate, reduce = _compiled_traced_closed_form(solver, inverse.order, rows, fk, jacobian, with_index,
                                                    max(m, n) * _EPS)
    return _integrand(model, lower, upper, evaluate, reduce, constants, parameters, with_index, extremes=extremes)


def device_cartesian_integrand(model: GeneratedModel, inverse: InverseKinematics, box: tuple[np.ndarray, np.ndarray],
                               *, with_index: bool = True, limits: Limits | None = None,
                               length: float | str | None = None,
                               extremes: Callable[[float, float], None] | None = None) -> Integrand:
    """The Cartesian integrand [1_W 1/kappa, 1_W] (``with_index``) or [1_W] over ``box`` of a model loaded with the
    JAX backend (:func:`cartesian_on_device`), its batches reduced on the device (see the module docstring).
    ``extremes``: called with the smallest and largest 1/kappa of each batch's reachable points (a sweep's kappa
    extremes, :mod:`symkin.design.sweep_metrics`)."""
    import jax.numpy as jnp

    if not cartesian_on_device(model, inverse):
        raise ValueError(f"{model.name}: the Cartesian integrand runs on JAX's device for a parallel mechanism's "
                         "closed-form ik without passive-joint limits, loaded with the JAX backend")
    joint_box = mechanism.joint_limits(model, limits)
    lower, upper = (np.asarray(b, dtype=np.float64) for b in box)
    if lower.shape != (inverse.dimension,):
        raise ValueError(f"the Cartesian box must have {inverse.dimension} coordinates, got {lower.shape}")
    m, n = len(mechanism.task_space(model)), joint_box.shape[0]
    revolute = mechanism.revolute_mask(model)
    scale = row_scale(model, joint_box, length) if with_index else np.ones(m)
    if isinstance(inverse, ClosedFormInverse):
        return _traced_closed_form_integrand(model, inverse, lower, upper, joint_box, scale, with_index, extremes)
    constants: dict[str, Any] = {
        "orientation": None, "unscale": None, "sign": None, "tolerance": None,
        "limits": jnp.asarray(joint_box), "revolute": jnp.asarray(revolute), "stops": stop_arguments(model),
        "scale": jnp.asarray(scale)}
    if isinstance(inverse, ConstantOrientationInverse):
        scaled_rates = scale[:, None] * inverse.model.rates     # S R
        constants.update(orientation=jnp.asarray(inverse.model.orientation), sign=inverse.sign,
                         unscale=jnp.asarray(np.linalg.inv(scaled_rates)))
        names: tuple[str, ...] = ("ik", "inverse_jacobian")
    else:
        assert isinstance(inverse, WorkingModeInverse), "cartesian_on_device admits these two"
        constants["tolerance"] = POSITION_ROUND_TRIP_TOLERANCE * inverse.size
        names = ("ik", "fk", "jacobian")
    unbound = {name: model.unbound(name) for name in names}
    functions = _Functions(unbound["ik"][0], *(unbound[name][0] if name in unbound else None
                                               for name in ("fk", "jacobian", "inverse_jacobian")))
    parameters = {name: values for name, (_, values) in unbound.items()}
    evaluate, reduce = _compiled(functions, with_index, max(m, n) * _EPS, bool(revolute.any()))

    return _integrand(model, lower, upper, evaluate, reduce, constants, parameters, with_index, extremes=extremes)


def orientations_on_device(model: GeneratedModel, with_index: bool = True) -> bool:
    """Whether the orientation integrand of a spherical platform runs fused on JAX's device: the model is loaded with
    the JAX backend and has the generated ``ik`` (and ``inverse_jacobian`` for the index)."""
    needed = {"ik", "inverse_jacobian"} if with_index else {"ik"}
    return loaded_with_jax(model) and mechanism.turns_only(model) and needed <= set(model.functions)


@functools.lru_cache(maxsize=32)
def _compiled_orientations(ik: Callable[..., Any], inverse_jacobian: Callable[..., Any] | None, with_index: bool,
                           threshold: float) -> tuple[Any, Any]:
    """(values, reduce) of the orientation integrand (:func:`device_orientation_integrand`), jitted once per generated
    ik and J^-1 and options: [w 1/kappa(J^-1 E^-1), w] with w = 1_W |cos pitch|, or [w]."""
    import jax
    import jax.numpy as jnp

    def values(p: Any, constants: dict[str, Any], parameters: dict[str, Any]) -> tuple[Any, Any]:
        q = ik(p, **parameters["ik"]).joints
        finite = jnp.all(jnp.isfinite(q), axis=-1)
        q = jnp.where(finite[:, None], q, 0.0)
        _, inside = within_limits(q, constants["limits"], constants["revolute"], xp=jnp)
        rows, offsets, lower, upper = constants["stops"]
        reachable = finite & inside & stops.within_stops(q, rows, offsets, lower, upper, xp=jnp)
        weight = jnp.where(reachable, jnp.abs(jnp.cos(p[:, 1])), 0.0)
        if not with_index:
            return weight[:, None], weight
        assert inverse_jacobian is not None, "the index needs J^-1"

        def inverse_condition(joints: Any, angles: Any) -> Any:
            inverse = inverse_jacobian(joints, angles, **parameters["inverse_jacobian"])
            return _device_inverse_condition(inverse @ cofactors.inverse(angular_velocity_matrix(angles, jnp), jnp),
                                             threshold)

        index = on_gathered_rows(reachable, REACHABLE_SHARES, inverse_condition, q, p)  # few orientations reachable
        return jnp.stack([weight * index, weight], axis=-1), index

    return (jax.jit(lambda *arguments: values(*arguments)[0]),
            jax.jit(lambda *arguments: reduced(*values(*arguments))))


def device_orientation_integrand(model: GeneratedModel, lower: np.ndarray, upper: np.ndarray, joint_box: np.ndarray,
                                 *, with_index: bool = True,
                                 extremes: Callable[[float, float], None] | None = None) -> Integrand:
    """The orientation integrand of :func:`symkin.analysis.orientations.orientation_integrand` over the roll-pitch-yaw
    box [lower, upper] of a spherical platform loaded with the JAX backend (:func:`orientations_on_device`), its
    batches reduced on the device (see the module docstring); ``extremes`` as :func:`device_cartesian_integrand`'s."""
    import jax.numpy as jnp

    ik, ik_values = model.unbound("ik")
    inverse_jacobian, inverse_values = model.unbound("inverse_jacobian") if with_index else (None, {})
    constants = {"limits": jnp.asarray(joint_box), "revolute": jnp.asarray(mechanism.revolute_mask(model)),
                 "stops": stop_arguments(model)}
    parameters = {"ik": ik_values, "inverse_jacobian": inverse_values}
    evaluate, reduce = _compiled_orientations(ik, inverse_jacobian, with_index, 3 * _EPS)
    return _integrand(model, lower, upper, evaluate, reduce, constants, parameters, with_index, mechanism.ANGLES,
                      extremes)

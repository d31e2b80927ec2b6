"""The metrics of one design of a sweep (:mod:`symkin.design.sweeps`), each a number per design.

* ``gci`` and ``volume``: the global conditioning index v = int_W 1/kappa dW / int_W dW
  (seed eq. 8.28) and the workspace measure int_W dW, from one quasi-Monte Carlo integration
  over ``symkin gci``'s default domain (:func:`design_integrand`): the joint limits with dW = |det J| dq
  (a parallel mechanism: its configurations in the working mode), a rotating platform's Cartesian
  box at its home orientation, a spherical platform's orientations (fused on JAX's device for a model loaded
  with JAX that the device decides); each with its 95 % confidence half-width.
  1/kappa is that of the Jacobian homogenized by the definition's characteristic length where the task space
  mixes translations and rotations (each design's own with ``"auto"``);
* ``kappa_min`` and ``kappa_max``: the extremes of kappa over the same integration points
  inside the workspace (sample extremes: the true minimum is at most ``kappa_min``, the true
  maximum at least ``kappa_max``);
* ``torque_peak``: the largest actuator effort that rendering a unit force at the TCP needs
  anywhere in the workspace, max_q max_i ||J_p[:, i](q)||_2 with tau = J_p^T F (seed eq. 8.35,
  J_p the position rows of the task Jacobian), in N m per N for a revolute actuator (a length:
  for a serial arm, joint i's largest lever arm to the TCP) and N per N for a prismatic one.
  Times the force to render, it sizes the actuators (seed Table 8.5, force transmission).  A
  sample extreme over its own 2^m Sobol points (m from the budget) in the joint limits.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

#: metrics a sweep can compute, and those it computes unless told otherwise
METRICS = ("gci", "volume", "kappa_min", "kappa_max", "torque_peak")
DEFAULT_METRICS = ("gci", "volume", "kappa_min", "kappa_max")
#: metrics that come with an error estimate (a column NAME_error)
ESTIMATED = ("gci", "volume")
#: statuses of a row
OK, EMPTY = "ok", "empty workspace"


def design_integrand(design: Any, length: float | str | None, record: Callable[[float, float], None]) -> Any:
    """The integrand of the GCI and workspace measure of one design over ``symkin gci``'s default domain, calling
    ``record(lowest, highest)`` with the extremes of 1/kappa over each batch's points inside the workspace: the
    joint limits (dW = |det J| dq, a parallel mechanism's configurations in its working mode); a platform that also
    rotates (Stewart-Gough): the Cartesian box of its workspace at its home orientation, reachability by its ik
    (:func:`~symkin.analysis.global_indices.cartesian_integrand`); a spherical platform: its orientations with the
    invariant measure of SO(3) (:func:`~symkin.analysis.orientations.orientation_integrand`).  For a model loaded
    with JAX whose integrand the device decides it is fused there (:mod:`symkin.analysis.device_integrand`,
    :mod:`symkin.analysis.device_cartesian`) and the extremes come back with each batch's moments; elsewhere the
    values come back and the extremes are taken from them.

    Raises:
        ValueError: legs without closed forms (rated on a continued grid by ``symkin gci``, not sampled here).
    """
    from symkin import mechanism
    from symkin.analysis import inverse, orientations
    from symkin.analysis.global_indices import cartesian_integrand_for, joint_space_integrand_for
    from symkin.mechanism import reach

    sampled = mechanism.sampling(design)
    if sampled is mechanism.Sampling.CONTINUATION:
        raise ValueError(f"{design.name}: legs without closed forms are rated by continuation over a grid "
                         "(symkin gci MODEL --set ... per design), which a sweep does not sample")
    held = reach.held_at(design, None)
    if sampled is mechanism.Sampling.ORIENTATIONS:
        return orientations.orientation_integrand(design, extremes=record)
    if isinstance(held, reach.ConstantOrientation):
        ik = inverse.inverse_kinematics_for(held)
        if ik is None:
            raise ValueError(f"{design.name}: a platform that also rotates is rated over its Cartesian workspace, "
                             "which needs its generated 'ik' (derive it)")
        return cartesian_integrand_for(held, ik, reach.bounding_box(held), length=length, extremes=record)
    return joint_space_integrand_for(design, length=length, extremes=record)


def evaluate_design(model: Any, values: dict[str, float], definition: Any) -> dict[str, Any]:
    """The metrics of one design ({column: value} and ``status``): ``model`` bound to the sweep's
    fixed values and then ``values``; ``definition`` a :class:`~symkin.design.sweeps.SweepDefinition`."""
    from symkin import mechanism
    from symkin.integration.integrators import integrate

    row: dict[str, Any] = {c: math.nan for c in definition.columns()[1 + len(definition.axes):-1]}
    try:
        design = model.bind(**{**dict(definition.fixed), **values})
        extremes = [math.inf, -math.inf]

        def record(lowest: float, highest: float) -> None:
            extremes[0], extremes[1] = min(extremes[0], lowest), max(extremes[1], highest)

        integrand = design_integrand(design, definition.length, record)
        with np.errstate(all="ignore"):
            result = integrate(integrand, "qmc", definition.samples, seed=definition.seed)
        measure = result.component(1)
        if not measure.value > 0.0:
            return {**row, "status": EMPTY}
        gci = result.ratio(0, 1)
        found: dict[str, tuple[float, ...]] = {
            "gci": (gci.value, gci.error), "volume": (measure.value, measure.error),
            "kappa_min": (1.0 / extremes[1] if extremes[1] > 0 else math.inf,),
            "kappa_max": (1.0 / extremes[0] if extremes[0] > 0 else math.inf,)}
        if "torque_peak" in definition.metrics:
            joints = mechanism.joint_limits(design)
            found["torque_peak"] = (torque_peak(design, joints[:, 0], joints[:, 1], definition.samples,
                                                definition.seed),)
        for metric in definition.metrics:
            row[metric] = float(found[metric][0])
            if metric in ESTIMATED:
                row[f"{metric}_error"] = float(found[metric][1])
        return {**row, "status": OK}
    except (ValueError, KeyError, ArithmeticError, np.linalg.LinAlgError) as err:
        return {**row, "status": f"failed: {type(err).__name__}: {err}"}


def torque_peak(model: Any, lower: np.ndarray, upper: np.ndarray, samples: int, seed: int) -> float:
    """max over Sobol configurations in [lower, upper] (in the working mode, for a parallel
    mechanism) of the largest column norm of J_p: the peak effort per unit TCP force (see above); for a model loaded
    with the JAX backend reduced on its device (:func:`symkin.analysis.device_integrand.device_torque_peak`)."""
    from symkin.analysis import device_integrand
    from symkin.numerics import sampling
    from symkin.mechanism.working_mode import jacobian_in_working_mode
    from symkin import mechanism

    q = sampling.sobol(lower, upper, max(4, int(math.log2(samples))), np.random.default_rng(seed))
    if device_integrand.on_device(model):    # a model loaded with JAX: the Jacobians stay on the device
        return device_integrand.device_torque_peak(model, q)
    with np.errstate(all="ignore"):
        J, in_mode = jacobian_in_working_mode(model, q)
    inside = np.ones(len(q), dtype=bool) if in_mode is None else in_mode
    levers = np.linalg.norm(J[:, list(mechanism.position_rows(model)), :], axis=1)    # (N, n): ||J_p[:, i]||
    levers = levers[inside & np.isfinite(levers).all(axis=1)]
    if not len(levers):
        raise ValueError("no configuration of the working mode among the sampled ones")
    return float(levers.max())

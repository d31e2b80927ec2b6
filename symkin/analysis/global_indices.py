"""Global conditioning index and workspace measure (seed eq. 8.28).

    GCI = v = int_W (1/kappa) dW / int_W dW

The integral runs over the workspace W with a measure dW that must be stated; two
domains of integration and two measures are offered:

* ``domain="joint"`` integrates over the box of joint limits Q, with
  - ``measure="cartesian"`` (default): dW = |det J(q)| dq, the Cartesian volume element
    of the TCP workspace pulled back to joint space (change of variables).  It equals
    the Cartesian measure where q -> TCP is one-to-one on Q; where several joint
    configurations reach the same point (e.g. elbow up and down both within limits),
    that point is counted once per configuration (measure with multiplicity).  It needs
    a square task Jacobian: for a position task space the measure is the workspace's
    area/volume in m^d; for a pose task space [x, y, z, wx, wy, wz] it is the invariant
    volume of SE(3) (m^3 rad^3);
  - ``measure="joint"``: dW = dq, the plain average over joint space (common in the
    literature, but it rates configurations, not places of the workspace);
* ``domain="cartesian"`` integrates over a Cartesian box containing the workspace with
  the indicator of reachability from an inverse kinematics
  (:class:`~symkin.mechanism.feasibility.InverseKinematics`): dW = 1_W(x) dx, each reachable
  point counted once, 1/kappa at the first feasible solution branch.  This is the
  formulation of parallel mechanisms, whose inverse kinematics is closed-form.

The index is 1/kappa by default (:func:`~symkin.numerics.conditioning.inverse_condition_number`);
any function of the Jacobians (..., m, n) -> (...) can replace it (e.g. the smooth
1/kappa_F, or a Table 8.5 criterion for a global force or speed index).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from symkin.analysis import device_cartesian, device_integrand
from symkin.numerics import conditioning
from symkin.mechanism import reach
from symkin.mechanism.working_mode import jacobian_in_working_mode
from symkin import mechanism
from symkin.integration.estimates import Estimate, IntegralEstimate
from symkin.mechanism.feasibility import InverseKinematics, feasible_configurations
from symkin.mechanism.stops import StopInequalities
from symkin.integration.integrand import Integrand
from symkin.integration.integrators import integrate
from symkin.mechanism import Limits
from symkin.mechanism.reach import bounding_box
from symkin.runtime.info import GeneratedModel

DOMAINS = ("joint", "cartesian")
MEASURES = ("cartesian", "joint")

Index = Callable[[np.ndarray], np.ndarray]
#: The index a model loaded with the JAX backend evaluates on its device (:mod:`symkin.analysis.device_integrand`).
DEFAULT_INDEX = conditioning.inverse_condition_number



def scaled_index(model: GeneratedModel, index: Index, length: float | str | None, limits: np.ndarray) -> Index:
    """The index, applied to the homogenized Jacobian when the task space mixes lengths and angles."""
    rows = mechanism.position_rows(model)
    L = reach.homogenizing_length(model, length, limits)
    if L is not None:
        return lambda J: index(conditioning.homogenize(J, L, rows))
    return index


def local_index(model: GeneratedModel, q: np.ndarray, *, index: Index = conditioning.inverse_condition_number,
                length: float | str | None = None, limits: Limits | None = None) -> np.ndarray:
    """The local index (1/kappa by default) at configurations q (..., n), through ``model.jacobian``.

    ``length`` homogenizes a task space that mixes translations and rotations (m, or
    ``"auto"`` for the characteristic length over the joint limits).
    """
    scored = scaled_index(model, index, length, mechanism.joint_limits(model, limits))
    return scored(mechanism.jacobian(model, q))


def singular(model: GeneratedModel, q: np.ndarray, *, threshold: float = 0.0, length: float | str | None = None,
             limits: Limits | None = None) -> np.ndarray:
    """Boolean (...): configurations whose 1/kappa is at most ``threshold`` (0: numerically singular)."""
    return local_index(model, q, length=length, limits=limits) <= threshold


def joint_space_integrand(model: GeneratedModel, *, index: Index | None = conditioning.inverse_condition_number,
                          measure: str = "cartesian", limits: Limits | None = None,
                          length: float | str | None = None,
                          jacobian: Callable[[np.ndarray], np.ndarray] | None = None) -> Integrand:
    """Integrand over the joint-limit box: components [w g, w] (or [w] without an index).

    w = |det J(q)| (``measure="cartesian"``) or 1 (``measure="joint"``); g = index(J(q)).

    Args:
        model: a loaded model (numpy or C backend).
        index: function of Jacobians (..., m, n) -> (...); None for the measure alone.
        measure: ``cartesian`` or ``joint`` (see module docstring).
        limits: joint-limit overrides (see :func:`symkin.mechanism.joint_limits`).
        length: characteristic length for mixed task spaces (m, or ``"auto"``).
        jacobian: the Jacobian function q -> J; default ``model.jacobian``.  For a parallel
            mechanism the default is J(q, fk(q)) restricted to the working mode
            (:func:`symkin.mechanism.working_mode.jacobian_in_working_mode`): w = 0 outside it.
    """
    if measure not in MEASURES:
        raise ValueError(f"unknown measure '{measure}'; choose one of {', '.join(MEASURES)}")
    box = mechanism.joint_limits(model, limits)
    def evaluate(q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:  # (J, working-mode mask or None)
        return jacobian_in_working_mode(model, q) if jacobian is None else (jacobian(q), None)
    n = box.shape[0]
    if measure == "cartesian":
        m = len(mechanism.task_space(model))
        if m != n:
            raise ValueError(f"{model.name}: the Cartesian measure |det J| dq needs a square task Jacobian, "
                             f"this one is {m} x {n}; use measure='joint' or the Cartesian domain")
    scored = scaled_index(model, index, length, box) if index is not None else None

    def function(q: np.ndarray) -> np.ndarray:
        J, inside = evaluate(q)
        weight = conditioning.absolute_determinant(J) if measure == "cartesian" else np.ones(len(q))
        if inside is not None:
            weight = np.where(inside, weight, 0.0)
        if scored is None:
            return weight[:, None]
        return np.stack([weight * scored(J), weight], axis=-1)

    components = ("index dW", "dW") if scored is not None else ("dW",)
    return Integrand(box[:, 0], box[:, 1], function, components, mechanism.coordinate_names(model))


def cartesian_integrand(model: GeneratedModel, inverse: InverseKinematics, box: tuple[np.ndarray, np.ndarray], *,
                        index: Index | None = conditioning.inverse_condition_number, limits: Limits | None = None,
                        length: float | str | None = None) -> Integrand:
    """Integrand over a Cartesian box: components [1_W g, 1_W] (or [1_W] without an index).

    1_W(x) is 1 where ``inverse`` has a solution within the joint limits; g = index(J(q(x))).
    """
    joint_box = mechanism.joint_limits(model, limits)
    revolute = mechanism.revolute_mask(model)
    stops = StopInequalities.of_model(model)
    lower, upper = (np.asarray(b, dtype=np.float64) for b in box)
    if lower.shape != (inverse.dimension,):
        raise ValueError(f"the Cartesian box must have {inverse.dimension} coordinates, got {lower.shape}")
    scored = scaled_index(model, index, length, joint_box) if index is not None else None

    def function(points: np.ndarray) -> np.ndarray:
        q, inside = feasible_configurations(inverse, points, joint_box, revolute, stops)
        indicator = inside.astype(np.float64)
        if scored is None:
            return indicator[:, None]
        values = np.zeros(len(points))
        if inside.any():
            values[inside] = scored(mechanism.jacobian(model, q[inside], points[inside]))
        return np.stack([values, indicator], axis=-1)

    axes = tuple("xyz"[a] for a in mechanism.position_axes(model))
    components = ("index dW", "dW") if scored is not None else ("dW",)
    return Integrand(lower, upper, function, components, axes, indicator=len(components) - 1)


def joint_space_integrand_for(model: GeneratedModel, *, index: Index | None = conditioning.inverse_condition_number,
                              measure: str = "cartesian", limits: Limits | None = None,
                              length: float | str | None = None, extremes: Extremes | None = None) -> Integrand:
    """The joint-space integrand (:func:`joint_space_integrand`'s components) where it is evaluated: fused on JAX's
    device for a model loaded with the JAX backend whose working mode its generated functions decide and the default
    index (:mod:`symkin.analysis.device_integrand`), else on the host; ``extremes`` as :func:`recording_extremes`."""
    if measure in MEASURES and device_integrand.on_device(model) and index in (None, DEFAULT_INDEX):
        return device_integrand.device_joint_space_integrand(model, with_index=index is not None, measure=measure,
                                                             limits=limits, length=length, extremes=extremes)
    return recording_extremes(joint_space_integrand(model, index=index, measure=measure, limits=limits,
                                                    length=length), extremes)


#: Called with the smallest and largest index of each batch's points inside the workspace (a sweep's kappa extremes).
Extremes = Callable[[float, float], None]


def recording_extremes(integrand: Integrand, extremes: Extremes | None) -> Integrand:
    """A host integrand [index dW, dW] that also calls ``extremes`` with the smallest and largest index of each
    batch's points inside the workspace (dW > 0), as the device's integrands do with their moments; itself without."""
    if extremes is None:
        return integrand
    host = integrand.function

    def recorded(points: np.ndarray) -> np.ndarray:
        out = host(points)
        inside = out[:, 1] > 0.0
        if inside.any():
            index = out[inside, 0] / out[inside, 1]
            extremes(float(index.min()), float(index.max()))
        return out

    return replace(integrand, function=recorded)


def cartesian_integrand_for(model: GeneratedModel, inverse: InverseKinematics, box: tuple[np.ndarray, np.ndarray], *,
                            index: Index | None = conditioning.inverse_condition_number, limits: Limits | None = None,
                            length: float | str | None = None, extremes: Extremes | None = None) -> Integrand:
    """The Cartesian integrand (:func:`cartesian_integrand`'s components) where it is evaluated: fused on JAX's
    device for a model loaded with the JAX backend whose closed-form ik the device decides and the default index
    (:mod:`symkin.analysis.device_cartesian`), else on the host; ``extremes`` as :func:`recording_extremes`."""
    if device_cartesian.cartesian_on_device(model, inverse) and index in (None, DEFAULT_INDEX):
        return device_cartesian.device_cartesian_integrand(model, inverse, box, with_index=index is not None,
                                                           limits=limits, length=length, extremes=extremes)
    return recording_extremes(cartesian_integrand(model, inverse, box, index=index, limits=limits, length=length),
                              extremes)


@dataclass(frozen=True)
class GlobalIndex:
    """A global index (GCI by default) with the workspace measure it was averaged over.

    Attributes:
        value: the global index (ratio of the two integrals) and its error.
        measure: int_W dW and its error (area/volume in m^d for a positional Cartesian measure).
        integral: the raw integrator result (both components).
        description: which domain and measure were used, in words.
        caveat: a warning about the error estimate, or "".
    """

    value: Estimate
    measure: Estimate
    integral: IntegralEstimate
    description: str
    caveat: str = ""


def _integrand(model: GeneratedModel, *, domain: str, measure: str, index: Index | None, limits: Limits | None,
               length: float | str | None, inverse: InverseKinematics | None,
               box: tuple[np.ndarray, np.ndarray] | None) -> tuple[Integrand, str]:
    if domain == "joint":
        integrand = joint_space_integrand_for(model, index=index, measure=measure, limits=limits, length=length)
        return integrand, reach.domain_description(model, domain, measure)
    if domain == "cartesian":
        if inverse is None:
            raise ValueError("the Cartesian domain needs an inverse kinematics (inverse=...)")
        if box is None:
            box = bounding_box(model, limits=limits)
        integrand = cartesian_integrand_for(model, inverse, box, index=index, limits=limits, length=length)
        return integrand, reach.domain_description(model, domain, measure)
    raise ValueError(f"unknown domain '{domain}'; choose one of {', '.join(DOMAINS)}")


def global_index(model: GeneratedModel, *, method: str = "qmc", samples: int = 2**16, seed: int | None = None,
                 domain: str = "joint", measure: str = "cartesian",
                 index: Index = conditioning.inverse_condition_number, limits: Limits | None = None,
                 length: float | str | None = None, inverse: InverseKinematics | None = None,
                 box: tuple[np.ndarray, np.ndarray] | None = None, **options) -> GlobalIndex:
    """Workspace average of an index of the Jacobian, int_W g dW / int_W dW, with error estimates.

    Args:
        model: a loaded model; its generated ``jacobian`` (and ``fk`` for the default
            Cartesian box) are evaluated on batches.
        method: integrator: ``grid``, ``mc``, ``qmc`` or ``adaptive``.
        samples: budget of integrand evaluations.
        seed: seed of the random methods.
        domain: ``joint`` or ``cartesian`` (see module docstring).
        measure: ``cartesian`` or ``joint`` (joint domain only).
        index: the local index, 1/kappa by default.
        limits: joint-limit overrides.
        length: characteristic length (m, or ``"auto"``) for a task space that mixes
            translations and rotations.
        inverse: inverse kinematics (Cartesian domain).
        box: Cartesian box (lower, upper) of the Cartesian domain; default: the
            workspace's :func:`~symkin.analysis.reach.bounding_box`.
        options: integrator options (``replicates``, ``rtol``).
    """
    integrand, description = _integrand(model, domain=domain, measure=measure, index=index, limits=limits,
                                        length=length, inverse=inverse, box=box)
    description += evaluation_site(model, integrand, method, _host_reason(domain, measure, index, inverse))
    result = integrate(integrand, method, samples, seed=seed, **options)
    caveat = ""
    if domain == "cartesian" and not result.statistical:
        caveat = (f"the reachability indicator is discontinuous: the {method} error estimate assumes that its "
                  "sample points see every crossing of the workspace boundary; mc and qmc give a confidence "
                  "interval without that assumption")
    return GlobalIndex(result.ratio(0, 1), result.component(1), result, description, caveat)


def evaluation_site(model: GeneratedModel, integrand: Integrand, method: str, host_reason: str) -> str:
    """Where the integrand of a model loaded with the JAX backend was evaluated, as a clause for a result's
    description: "; fused on JAX's <backend> device" (cpu, gpu) where its batches were reduced there, else "; the JAX code
    evaluated point by point, its values reduced on the host (<why>)", so that --backend jax never falls back
    silently; "" for the other backends."""
    if not device_integrand.loaded_with_jax(model):
        return ""
    if integrand.moments is not None and method != "adaptive":
        import jax

        return f"; fused on JAX's {jax.default_backend()} device"
    why = "the adaptive integrator refines on the values" if integrand.moments is not None else host_reason
    return f"; the JAX code evaluated point by point, its values reduced on the host ({why})"


def _host_reason(domain: str, measure: str, index: Index | None, inverse: InverseKinematics | None) -> str:
    """Why a model loaded with JAX takes the host integrand (:func:`joint_space_integrand_for`,
    :func:`cartesian_integrand_for`), in words."""
    if index not in (None, DEFAULT_INDEX):
        return "the device program computes 1/kappa, not another index"
    if domain == "joint":
        if measure not in MEASURES:
            return f"the measure {measure!r}"
        return "the working mode is decided on the loop closure: legs without closed forms or passive-joint limits"
    if getattr(inverse, "passive_limits", None) is not None:
        return "the passive-joint limits are decided on the loop closure"
    return "this inverse kinematics does not trace in jax.numpy"


def gci(model: GeneratedModel, **kwargs) -> GlobalIndex:
    """The global conditioning index v = int_W 1/kappa dW / int_W dW (seed eq. 8.28).

    Keyword arguments as :func:`global_index` (whose default index is 1/kappa).
    """
    kwargs.setdefault("index", conditioning.inverse_condition_number)
    return global_index(model, **kwargs)


def workspace_measure(model: GeneratedModel, *, method: str = "qmc", samples: int = 2**16, seed: int | None = None,
                      domain: str = "joint", limits: Limits | None = None,
                      inverse: InverseKinematics | None = None,
                      box: tuple[np.ndarray, np.ndarray] | None = None, **options) -> Estimate:
    """Area or volume of the workspace, int_W dW, with its error estimate.

    ``domain="joint"`` integrates |det J| dq over the joint limits (exact where the map is
    one-to-one; overlapping branches counted with multiplicity); ``domain="cartesian"``
    integrates the reachability indicator over a Cartesian box (each point once).
    """
    integrand, _ = _integrand(model, domain=domain, measure="cartesian", index=None, limits=limits,
                              length=None, inverse=inverse, box=box)
    return integrate(integrand, method, samples, seed=seed, **options).component(0)

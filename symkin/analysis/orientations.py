"""The orientation workspace of a spherical platform (p = roll, pitch, yaw) and its global conditioning.

A spherical parallel mechanism (the Agile Eye) turns its platform about a fixed centre: its workspace
is a set of orientations, measured with the invariant (Haar) measure of SO(3).  In the task coordinates
p = (roll, pitch, yaw), R = Rz(yaw) Ry(pitch) Rx(roll), that measure is

    dW = |cos(pitch)| d(roll) d(pitch) d(yaw)            (rad^3; all of SO(3): 8 pi^2 = 78.96 rad^3),

|det E| with omega = E d(roll, pitch, yaw)/dt (:func:`symkin.mechanism.reach.angular_velocity_matrix`),
the volume element that does not depend on how the orientations are parametrized (Chirikjian and Kyatkin,
Engineering Applications of Noncommutative Harmonic Analysis, 2001, sec. 9.2).  Its conditioning is that
of the angular-velocity Jacobian J_w = E (J^-1)^-1 (omega = J_w qdot), whose condition number does not
depend on the angles either; kappa(J_w) = kappa(J^-1 E^-1), formed without inverting J^-1.

The workspace is integrated over the roll-pitch-yaw box (the whole chart of SO(3) by default: roll and
yaw over a full turn, pitch over [-90, 90] deg, each orientation once) with reachability from the
generated closed-form ``ik`` (every leg reaches p on its declared branch, the joints within their limits; for a
model loaded with the JAX backend on its device, :func:`symkin.analysis.device_cartesian.device_orientation_integrand`):

    GCI = int_W 1/kappa(J_w) dW / int_W dW.
"""

from __future__ import annotations

import numpy as np

from symkin.numerics import conditioning
from symkin import mechanism
from symkin.analysis import device_cartesian
from symkin.analysis.global_indices import Extremes, GlobalIndex, evaluation_site, recording_extremes
from symkin.integration.integrand import Integrand
from symkin.integration.integrators import integrate
from symkin.mechanism.limits import within_limits
from symkin.mechanism import stops
from symkin.numerics.sobol import Sobol
from symkin.mechanism import Limits
from symkin.mechanism.reach import angular_velocity_matrix
from symkin.mechanism.working_mode import require_functions
from symkin.runtime.info import GeneratedModel

#: The roll-pitch-yaw chart of SO(3): each orientation once (up to the measure-zero gimbal-lock set).
FULL_CHART = (np.array([-np.pi, -np.pi / 2, -np.pi]), np.array([np.pi, np.pi / 2, np.pi]))
#: The measure of all of SO(3) in rad^3.
SO3_MEASURE = 8 * np.pi**2


def inverse_condition(model: GeneratedModel, q: np.ndarray, p: np.ndarray) -> np.ndarray:
    """1/kappa of the angular-velocity Jacobian at consistent (q, p): of J^-1 E^-1 (0 where singular)."""
    E = angular_velocity_matrix(p)
    with np.errstate(invalid="ignore", divide="ignore"):
        inverse = np.einsum("...ij,...jk->...ik", model.inverse_jacobian(q, p), np.linalg.inv(E))
    finite = np.isfinite(inverse).all(axis=(-2, -1))
    out = np.zeros(np.shape(finite))
    out[finite] = conditioning.inverse_condition_number(inverse[finite])
    return out


def _reachable(model: GeneratedModel, p: np.ndarray, joint_box: np.ndarray, revolute: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """(q, reachable) at orientations p: every leg reaches p on its declared branch, the joints within their limits."""
    with np.errstate(invalid="ignore"):  # NaN where a leg cannot reach: unreachable
        q = np.asarray(model.ik(p).joints)
    inside = np.isfinite(q).all(axis=-1)
    inside[inside] = within_limits(q[inside], joint_box, revolute)[1] & stops.respected(model, q[inside])
    return q, inside


def _index(model: GeneratedModel, p: np.ndarray, joint_box: np.ndarray, revolute: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """(1/kappa of J_w, 0 where unreachable; reachable) at orientations p."""
    q, inside = _reachable(model, p, joint_box, revolute)
    values = np.zeros(len(p))
    if inside.any():
        values[inside] = inverse_condition(model, q[inside], p[inside])
    return values, inside


def reachable_index(model: GeneratedModel, p: np.ndarray, limits: Limits | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(1/kappa of J_w, 0 where unreachable; whether reachable) at orientations p (N, 3), as the GCI sees them."""
    return _index(model, p, mechanism.joint_limits(model, limits), mechanism.revolute_mask(model))


def orientation_integrand(model: GeneratedModel, box: tuple[np.ndarray, np.ndarray] = FULL_CHART, *,
                          limits: Limits | None = None, index: bool = True,
                          extremes: Extremes | None = None) -> Integrand:
    """Components [1_W |cos pitch| 1/kappa, 1_W |cos pitch|] (or the measure alone) over a roll-pitch-yaw box;
    ``extremes`` as :func:`symkin.analysis.global_indices.recording_extremes`.

    Raises:
        ValueError: the model is not a spherical platform with generated ``ik`` and ``inverse_jacobian``.
    """
    if not mechanism.turns_only(model):
        raise ValueError(f"{model.name}: the orientation workspace is that of a spherical platform (task coordinates "
                         f"roll, pitch, yaw), not of {list(mechanism.task_space(model))}")
    require_functions(model, ("ik", "inverse_jacobian") if index else ("ik",))
    joint_box = mechanism.joint_limits(model, limits)
    revolute = mechanism.revolute_mask(model)
    lower, upper = (np.asarray(b, dtype=np.float64) for b in box)
    if device_cartesian.orientations_on_device(model, index):  # loaded with JAX: fused and reduced on its device
        return device_cartesian.device_orientation_integrand(model, lower, upper, joint_box, with_index=index,
                                                             extremes=extremes)

    def function(p: np.ndarray) -> np.ndarray:
        if not index:
            return np.where(_reachable(model, p, joint_box, revolute)[1], np.abs(np.cos(p[:, 1])), 0.0)[:, None]
        values, inside = _index(model, p, joint_box, revolute)
        weight = np.where(inside, np.abs(np.cos(p[:, 1])), 0.0)
        return np.stack([weight * values, weight], axis=-1)

    components = ("index dW", "dW") if index else ("dW",)
    return recording_extremes(Integrand(lower, upper, function, components, mechanism.ANGLES,
                                        indicator=len(components) - 1), extremes)


def orientation_cloud(model: GeneratedModel, samples: int = 2**14, *, seed: int = 0,
                      box: tuple[np.ndarray, np.ndarray] = FULL_CHART, limits: Limits | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(p, 1/kappa): the reachable orientations among ``samples`` (rounded up to a power of 2) scrambled Sobol
    points of the roll-pitch-yaw box (their density in the chart is uniform, not Haar: a picture; the measure is
    :func:`orientation_gci`'s)."""
    integrand = orientation_integrand(model, box, limits=limits)
    unit = Sobol(3, np.random.default_rng(seed)).points(0, 2**max(1, int(np.ceil(np.log2(samples)))))
    points = unit * (integrand.upper - integrand.lower) + integrand.lower
    values = integrand.function(points)
    reachable = values[:, 1] > 0  # the weight |cos pitch| of a reachable orientation (pitch = +-90 deg: never drawn)
    return points[reachable], values[reachable, 0] / values[reachable, 1]


def orientation_gci(model: GeneratedModel, *, method: str = "qmc", samples: int = 2**16, seed: int | None = None,
                    box: tuple[np.ndarray, np.ndarray] = FULL_CHART, limits: Limits | None = None,
                    **options) -> GlobalIndex:
    """GCI over the orientation workspace and its Haar measure in rad^3 (see the module docstring)."""
    integrand = orientation_integrand(model, box, limits=limits)
    result = integrate(integrand, method, samples, seed=seed, **options)
    description = ("orientations (roll, pitch, yaw) with reachability from the closed-form ik, dW = |cos pitch| "
                   "droll dpitch dyaw: the invariant measure of SO(3) in rad^3 (all orientations: 8 pi^2 = 78.96)"
                   + evaluation_site(model, integrand, method, "the model lacks the generated ik or inverse_jacobian"))
    caveat = "" if result.statistical else ("the reachability indicator is discontinuous: mc and qmc give a "
                                            "confidence interval without assumptions on the boundary")
    return GlobalIndex(result.ratio(0, 1), result.component(1), result, description, caveat)

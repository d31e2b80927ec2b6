"""The working mode of a parallel mechanism with closed forms: where its actuated joints assemble it in the model's
declared branches (``ik_branch``, ``fk_branch``), as the run-time mechanism answers it for every analysis.

A configuration q is in the working mode where fk(q) assembles, ik(fk(q)) = q (the same leg branches, not the
other root of a leg reached through a leg singularity) and the declared passive-joint limits hold
(:mod:`symkin.mechanism.passive`); on that set q <-> p is one-to-one (see :mod:`symkin.mechanism.reach` for
what the analyses build on it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin import mechanism
from symkin.mechanism import passive, stops
from symkin.mechanism.limits import wrap_angle
from symkin.runtime.info import GeneratedModel

#: Largest |ik(fk(q)) - q| (rad or m) of a configuration in the working mode.  The two
#: roots of a leg differ by far more except next to the leg singularity where they
#: meet, and there the integrand vanishes.
JOINT_ROUND_TRIP_TOLERANCE = 1e-6

def require_functions(model: GeneratedModel, names: tuple[str, ...]) -> None:
    """Refuse a model without the generated parallel functions ``names`` (the message names the fix)."""
    for name in names:
        mechanism.parallel_function(model, name)


def working_mode(model: GeneratedModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """TCP positions of configurations q (..., n) and whether each is in the working mode.

    Returns:
        (p, inside): p = fk(q) (..., 3), NaN where the legs cannot be assembled; inside:
        boolean (...), fk assembles, ik(fk(q)) = q and the declared passive-joint limits hold
        (the actuators' joint limits are not checked here).
    """
    require_functions(model, ("fk", "ik"))
    q = np.asarray(q, dtype=np.float64)
    with np.errstate(invalid="ignore"):  # the closed forms take sqrt of negative margins: NaN, as documented
        p = model.fk(q).position
        back = model.ik(np.where(np.isfinite(p), p, 0.0)).joints
        inside = same_branches(q, p, back, mechanism.revolute_mask(model))
    limits = passive.declared_limits(model)
    if limits is not None:
        batch = inside.shape
        inside = passive.admissible(model, limits, q.reshape(-1, q.shape[-1]), p.reshape(-1, p.shape[-1]),
                                    inside.reshape(-1)).reshape(batch)
    return p, inside


def same_branches(q: Any, p: Any, back: Any, revolute: Any, xp: Any = np) -> Any:
    """Whether each configuration q (..., n) assembles in the working mode: fk(q) = p is finite and ik(p) = ``back``
    returns q to :data:`JOINT_ROUND_TRIP_TOLERANCE` (angles, ``revolute`` (n,), compared modulo 2 pi), in the array
    module ``xp`` (numpy, or jax.numpy on a JAX device)."""
    error = xp.abs(xp.where(revolute, wrap_angle(back - q, xp), back - q))
    return xp.isfinite(p).all(axis=-1) & xp.all(error <= JOINT_ROUND_TRIP_TOLERANCE, axis=-1)


def assembly_functions(model: GeneratedModel) -> tuple[str, ...] | None:
    """The generated functions that decide, wherever they run (a JAX device too), which configurations of ``model``
    assemble in its working mode: () where every configuration does (an open chain; its joint stops aside),
    ("fk", "ik") for a mechanism that closes loops through closed forms (fk(q) assembles and ik(fk(q)) = q, as
    :func:`working_mode` decides), None where the question needs this module's host code: declared passive-joint
    limits (evaluated on the closure, :mod:`symkin.mechanism.passive`), legs without closed forms (continued),
    a device carrying a wrist."""
    if model.info.mechanism == "serial":
        return ()
    if (mechanism.is_parallel(model) and {"fk", "ik", "jacobian"} <= set(model.functions)
            and not any(model.info.passive_limits)):
        return ("fk", "ik")
    return None


def assemble(model: GeneratedModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The assembly question of every analysis: the handle's positions (..., d) at configurations q (..., n) and
    whether each configuration belongs to the workspace (...).  A mechanism that closes loops: fk(q) in the
    working mode (:func:`working_mode`); an open chain: its TCP (every configuration belongs, but where the view
    of a device yields no position: a hybrid device's configurations whose legs do not assemble).  Either way only
    the configurations within the model's joint stops belong (:mod:`symkin.mechanism.stops`)."""
    if mechanism.is_parallel(model):
        points, inside = working_mode(model, q)
    else:
        points = mechanism.tcp_positions(model, q)
        inside = np.isfinite(points).all(axis=-1)
    return points, inside & stops.respected(model, q)


def jacobian_in_working_mode(model: GeneratedModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The task Jacobian at configurations q and the working-mode mask (...) of a mechanism that closes loops:
    J(q, fk(q)) (..., 3, n) and :func:`working_mode`'s mask; an open chain's J(q) and None (every configuration
    counts) or, where the model declares joint stops, the configurations within them."""
    if not mechanism.is_parallel(model):
        return mechanism.jacobian(model, q), stops.respected(model, q) if model.info.joint_stops else None
    p, inside = working_mode(model, q)
    return model.jacobian(q, np.where(np.isfinite(p), p, 0.0)), inside & stops.respected(model, q)

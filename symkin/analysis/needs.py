"""What each analysis evaluates of a model's generated code, by kind of mechanism: the one declared table a model
file is derived from on the fly (issue 62: it replaces the tables each command kept).

A kind's tuple is what the analysis calls for every model of that kind: a serial arm's fk and J; a translational
platform's closed-form ik (reachability, working mode) with its fk and J; a platform that also rotates
(Stewart-Gough: no closed-form fk) and a spherical one (the Agile Eye) through ik and J^-1.  Legs without the
distance form are derived with the closure's functions instead (``symkin.analysis.model_files.CLOSURE_OUTPUTS``);
what a model has only sometimes (gravity, a wrist) is asked for as optional.  :data:`DERIVED` holds what the
commands that derive more than a tuple by kind (identify, excite) derive a model file with, legs without the
distance form included.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

from symkin import mechanism
from symkin.mechanism import MechanismKind

#: The dynamics a simulation integrates and checks (its energy balance).
SIMULATED_DYNAMICS = ("forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy", "coriolis_vector")

#: {analysis: {kind of mechanism: the generated functions it evaluates}}.
NEEDS: Mapping[str, Mapping[MechanismKind, tuple[str, ...]]] = {
    # workspace, gci, sweep and the other kinematic analyses
    "kinematics": {MechanismKind.SERIAL: ("fk", "jacobian"),
                   MechanismKind.PARALLEL: ("ik", "fk", "jacobian"),
                   MechanismKind.PARALLEL_POSE: ("ik", "inverse_jacobian"),
                   MechanismKind.PARALLEL_ORIENTATION: ("ik", "inverse_jacobian")},
    # the haptic datasheet (symkin.rating.datasheet): also the mass matrix (apparent mass)
    "rate": {MechanismKind.SERIAL: ("fk", "jacobian", "mass_matrix"),
             MechanismKind.PARALLEL: ("ik", "fk", "jacobian", "mass_matrix"),
             MechanismKind.PARALLEL_POSE: ("ik", "inverse_jacobian"),
             MechanismKind.PARALLEL_ORIENTATION: ("ik", "inverse_jacobian", "jacobian", "mass_matrix")},
    # a dimensioning program (symkin.design; a spherical platform's rating also takes J^-1:
    # symkin.analysis.orientations)
    "design": {MechanismKind.SERIAL: ("fk", "jacobian"),
               MechanismKind.PARALLEL: ("ik", "jacobian"),
               MechanismKind.PARALLEL_POSE: ("ik", "inverse_jacobian"),
               MechanismKind.PARALLEL_ORIENTATION: ("ik", "jacobian", "inverse_jacobian")},
    # the scenarios of symkin.simulation: the kinematics of the handle and the dynamics
    "simulate": {MechanismKind.SERIAL: ("fk", "jacobian", "jacobian_geometric") + SIMULATED_DYNAMICS,
                 MechanismKind.PARALLEL: ("ik", "fk", "jacobian") + SIMULATED_DYNAMICS,
                 MechanismKind.PARALLEL_POSE: ("ik", "inverse_jacobian") + SIMULATED_DYNAMICS,
                 MechanismKind.PARALLEL_ORIENTATION: ("ik", "fk", "jacobian") + SIMULATED_DYNAMICS},
    # symkin view (symkin.viewer.page): a translational platform driven through its closed-form ik and rated by J
    # (its cloud from the closed-form fk); a pose platform (no closed-form fk) by the twist Jacobian from J^-1, at
    # the home orientation for the cloud; the legs drawn from leg_points
    "view": {MechanismKind.SERIAL: ("fk", "frames", "jacobian"),
             MechanismKind.PARALLEL: ("ik", "fk", "leg_points", "jacobian", "singularities"),
             MechanismKind.PARALLEL_POSE: ("ik", "leg_points", "inverse_jacobian", "singularities"),
             MechanismKind.PARALLEL_ORIENTATION: ("ik", "leg_points", "inverse_jacobian", "singularities")},
}


#: {analysis: what it evaluates of a model sampled by continuation (legs without closed forms: the closure alone)}, where
#: it differs from ``symkin.analysis.model_files.CLOSURE_OUTPUTS``.
CONTINUED_NEEDS: Mapping[str, tuple[str, ...]] = {
    # a dimensioning program: each point of the required box with its assembly (q, s) as variables
    "design": ("closure", "closure_jacobians"),
}


def needs_of(analysis: str, model) -> tuple[str, ...]:
    """The generated functions ``analysis`` evaluates of the loaded ``model``: its row of :data:`NEEDS` for the
    model's kind, or :data:`CONTINUED_NEEDS` for a model sampled by continuation."""
    if mechanism.sampling(model) is mechanism.Sampling.CONTINUATION:
        return CONTINUED_NEEDS[analysis]
    return NEEDS[analysis][mechanism.kind_of(model)]


class Derived(NamedTuple):
    """What a command derives a model file with when its needs are not one tuple by kind (the ``outputs``,
    ``optional`` and ``closure`` of :func:`symkin.analysis.model_files.generated_model`, in that order)."""

    #: derived for every model
    outputs: tuple[str, ...]
    #: also derived where the model has them, by kind of mechanism
    optional: Mapping[MechanismKind, tuple[str, ...]]
    #: derived instead of ``outputs`` where the legs have no distance form (the closure's functions)
    closure: tuple[str, ...]

    def required_of(self, functions: Sequence[str]) -> tuple[str, ...]:
        """What a generated directory with ``functions`` needs of these: the closure's functions where it has the
        closure's regressors (legs without the distance form), else ``outputs``."""
        return self.closure if "closure_regressor" in functions else self.outputs


def _besides_open_chains(names: Sequence[str]) -> dict[MechanismKind, tuple[str, ...]]:
    """``names`` for every kind of mechanism that closes loops, none for an open chain."""
    return {kind: () if kind is MechanismKind.SERIAL else tuple(names) for kind in MechanismKind}


#: What a run's regressors need: the base regressor (the estimate), the standard one (the consistent estimate and the
#: model file), and a parallel model's poses from its closed-form fk or by Newton on its leg equations; legs without
#: the distance form take the closure (each sample's assembly), its dynamics (the velocities and accelerations it
#: allows) and the regressors over all its variables.
_IDENTIFIED = ("base_regressor", "regressor")
_POSES = ("fk", "constraints", "constraint_jacobians")
_CLOSURE_IDENTIFIED = ("closure", "closure_jacobians", "closure_dynamics", "closure_regressor",
                       "closure_base_regressor")

#: {command: what it derives a model file with}.
DERIVED: Mapping[str, Derived] = {
    # symkin identify (symkin.identification.device_regressors), and with --method energy
    "identify": Derived(_IDENTIFIED, _besides_open_chains(_POSES), _CLOSURE_IDENTIFIED),
    "identify energy": Derived((*_IDENTIFIED, "energy_regressor"), _besides_open_chains(_POSES),
                               (*_CLOSURE_IDENTIFIED, "closure_energy_regressor")),
    # symkin excite (symkin.identification.excitation): the base regressor along a parallel model's motion through fk, or its
    # pose's through ik without a closed-form fk; legs without the distance form: the actuators' series, each sample
    # assembled by a rootfinder (symkin.identification.closure_excitation)
    "excite": Derived(("base_regressor",), _besides_open_chains(("fk", "ik")),
                      ("closure", "closure_jacobians", "closure_dynamics", "closure_base_regressor")),
}

"""What each analysis evaluates of a model's generated code, by kind of mechanism: the one declared table a model
file is derived from on the fly (issue 62: it replaces the tables each command kept).

A kind's tuple is what the analysis calls for every model of that kind: a serial arm's fk and J; a translational
platform's closed-form ik (reachability, working mode) with its fk and J; a platform that also rotates
(Stewart-Gough: no closed-form fk) and a spherical one (the Agile Eye) through ik and J^-1.  Legs without the
distance form are derived with the closure's functions instead (``symkin.analysis.model_files.CLOSURE_OUTPUTS`` and
each command's own closure list); what a model has only sometimes (gravity, a wrist) is asked for as optional.
"""

from __future__ import annotations

from collections.abc import Mapping

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
    # the haptic datasheet (symkin.analysis.datasheet): also the mass matrix (apparent mass)
    "rate": {MechanismKind.SERIAL: ("fk", "jacobian", "mass_matrix"),
             MechanismKind.PARALLEL: ("ik", "fk", "jacobian", "mass_matrix"),
             MechanismKind.PARALLEL_POSE: ("ik", "inverse_jacobian"),
             MechanismKind.PARALLEL_ORIENTATION: ("ik", "inverse_jacobian", "jacobian", "mass_matrix")},
    # a dimensioning program (symkin.design; a spherical platform's rating also takes J^-1:
    # symkin.analysis.orientations)
    "design": {MechanismKind.SERIAL: ("fk", "jacobian"),
               MechanismKind.PARALLEL: ("ik", "jacobian"),
               MechanismKind.PARALLEL_POSE: ("ik", "jacobian"),
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


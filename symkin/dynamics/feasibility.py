"""What a model's dynamics can be derived for: the mass matrix that ``forward_dynamics`` inverts.

``forward_dynamics`` solves M(q) qdd = tau - V - G - F_f by a symbolic LDL^T factorization
(:mod:`symkin.dynamics.linsolve`), which divides by the pivots of M.  A model whose M is
singular at every configuration (a joint that moves no mass and no rotational inertia, such
as a SCARA with a point mass on its last revolute axis) would give pivots that are
identically zero, so the derivation must refuse it before it starts.  ``symkin check`` and
``symkin derive`` both call :func:`mass_matrix_problems` through
:func:`symkin.pipeline.resolve_request`, so a model that ``check`` accepts never stops
``derive`` with a traceback.

The test is numeric, at a few configurations within the joint limits: M (parameters at their
defaults) is symmetric positive semidefinite by construction, its eigenvalues computed by
LAPACK are exact for M + E with ||E|| <= p(n) u ||M|| (LAPACK Users' Guide, sec. 4.7), so an
eigenvalue below :data:`SINGULAR_RELATIVE` n eps max|lambda| cannot be told from zero; M is
refused when that holds at every sample (singular for all q, not at an isolated
configuration, which the solve then meets as a singular configuration at run time), or when
an eigenvalue is negative beyond that bound (indefinite: inertias that are not physical).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from symkin.derivation import Derivation, registry
from symkin.errors import Problem
from symkin.ir.evaluate import lambdify_spec
from symkin.model.coordinates import coordinate_range
from symkin.model.schema import Model

#: Eigenvalue bound, in units of n eps max|lambda|, below which M is numerically singular.
SINGULAR_RELATIVE = 64.0
#: Configurations at which M is evaluated (a singular M at all of them is singular everywhere:
#: det M is an analytic function of q, zero on a set of positive measure only if identically zero).
SAMPLES = 4


def mass_matrix_problems(model: Model, outputs: Sequence[str]) -> list[Problem]:
    """Problems that stop the derivation of ``outputs``: an M that they invert and that is singular
    at every configuration, or an indefinite M; empty when nothing asked for inverts M."""
    if model.mechanism != "serial":
        return []
    quantities = registry(model.mechanism)
    inverting = [name for name in outputs if name in quantities and quantities[name].solves_with == "mass_matrix"]
    if not inverting:
        return []
    spec = Derivation(model)["mass_matrix"]
    evaluate = lambdify_spec(spec, [list(i.symbols) for i in spec.vector_inputs], "numpy", model.parameter_values)
    n = model.dof
    rng = np.random.default_rng(0)
    singular_everywhere, null_direction = True, None
    lower, upper = coordinate_range(model)
    for q in rng.uniform(lower, upper, (SAMPLES, n)):
        M = np.array(evaluate(q), dtype=float).reshape(n, n)
        eigenvalues, vectors = np.linalg.eigh(M)
        scale = float(np.max(np.abs(eigenvalues)))
        bound = SINGULAR_RELATIVE * n * np.finfo(float).eps * scale
        if eigenvalues[0] < -bound:
            return [model.problem(("bodies",), f"the mass matrix is indefinite at q = {np.round(q, 3).tolist()} "
                                                f"(eigenvalue {eigenvalues[0]:.3g}): the bodies' inertias are not "
                                                "physical", "check the inertia tensors (each must be positive "
                                                                 "semidefinite and satisfy the triangle inequality)")]
        if scale > 0 and eigenvalues[0] > bound:
            singular_everywhere = False
            break
        null_direction = vectors[:, 0] if scale > 0 else None
    if not singular_everywhere:
        return []
    if null_direction is None:  # M = 0: nothing has mass
        return [model.problem(("bodies",), f"the mass matrix is zero: the model has no body with mass, so "
                                           f"{', '.join(inverting)} (which inverts M) cannot be derived",
                              "declare the bodies with their masses and inertias, or leave "
                              f"{', '.join(inverting)} out of the outputs (symkin derive --only ...)")]
    weights = np.abs(null_direction)
    joints = ", ".join(model.coordinates[j].name for j in np.flatnonzero(weights >= 0.5 * weights.max()))
    return [model.problem(("bodies",), f"the mass matrix is singular at every configuration: moving {joints} moves "
                                       "no mass and no rotational inertia (e.g. a point mass on a revolute axis), so "
                                       f"{', '.join(inverting)} (which inverts M) cannot be derived",
                          f"give the bodies that {joints} moves a mass off its axis or an inertia about it (e.g. the "
                          f"actuator's rotor inertia), or leave {', '.join(inverting)} out of the outputs "
                          "(symkin derive --only ...)")]

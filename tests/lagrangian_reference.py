"""The Lagrangian closed forms as a test reference for the emitted dynamics (kept out of the product).

M = sum over bodies of m Jv^T Jv + Jw^T I Jw, C from the Christoffel symbols of that M, V = C qd,
G = du/dq and tau = M qdd + V + G + F_f (seed eqs. 8.31-8.34), from :mod:`symkin.dynamics.lagrange`:
independent of the composite-rigid-body and Newton-Euler code that symkin emits.
"""

from __future__ import annotations

import functools

from symkin.derivation import Derivation
from symkin.dynamics import lagrange
from symkin.dynamics.program import Program, mat_vec, se_vector
from symkin.dynamics.quantities import function_spec
from symkin.ir.spec import FunctionSpec
from symkin.model import coordinates


@functools.lru_cache(maxsize=None)
def lagrangian_dynamics(d: Derivation) -> FunctionSpec:
    """M, C, V, G (with gravity) and tau of ``d.model`` from the Lagrangian closed forms, as one function spec."""
    n = d.model.dof
    q, qd, qdd = (se_vector(coordinates.symbols(d.model, group)) for group in ("q", "qd", "qdd"))
    program = Program()
    M_graph = lagrange.mass_matrix(d["body_jacobians"], n)
    M_flat = program.bind([v for row in M_graph for v in row])
    M = [M_flat[i * n:(i + 1) * n] for i in range(n)]
    partial_values = program.bind([v for dM in lagrange.mass_matrix_partials(M_graph, q) for row in dM for v in row])
    partials = [[partial_values[k * n * n + i * n:k * n * n + (i + 1) * n] for i in range(n)] for k in range(n)]
    C, V = lagrange.coriolis_matrix(partials, qd), lagrange.coriolis_vector(partials, qd)
    gravity = d["gravity_graph"]
    G = None if gravity is None else program.bind(
        lagrange.gravity_vector(d["body_jacobians"], d["chain"].axes, gravity))
    tau = [a + b for a, b in zip(V, mat_vec(M, qdd))]
    for extra in (G, d["friction_graph"]):
        if extra is not None:
            tau = [a + b for a, b in zip(tau, extra)]
    outputs = [("M", [v for row in M for v in row], (n, n)), ("C", [v for row in C for v in row], (n, n)),
               ("V", V, (n,))] + ([("G", G, (n,))] if G is not None else []) + [("tau", tau, (n,))]
    return function_spec(d, "lagrangian_dynamics", "Lagrangian reference dynamics.", "seed eqs. 8.31-8.34",
                         ["q", "qd", "qdd"], program,
                         [(name, entries, shape, name, "") for name, entries, shape in outputs])

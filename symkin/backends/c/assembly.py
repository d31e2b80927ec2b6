"""The generated assembly of a parallel model in C (issue 63): forward kinematics and J = dp/dq of any leg topology
from its generated loop closure, for servo loops (templates/c/source.c.j2, ``assembly``).

Where a model's C code holds ``closure`` and ``closure_jacobians`` (double precision), the source also gets

* ``<model>_assemble(q, s, p, params..., max_iterations, tolerance, residual)``: Gauss-Newton on phi(q, s, p) = 0
  for the passive joints s and the platform pose p at the actuated joints q, started from the given (s, p) - a
  control loop's previous sample - and written back into them: each step the least-squares solution of
  [Phi_s Phi_p] (ds, dp) = -phi, converged when a step's max-norm is at most ``tolerance`` (the run-time
  :func:`symkin.runtime.parallel.solve_closure`'s rule) or a step left every row of phi at rounding level
  (64 eps max(1, |p|): another step would be below rounding, and forming the Jacobians for it is the cost of a
  warm-started servo sample); returns the steps taken, or 0 with s and p set to NaN where
  it did not converge within ``max_iterations`` or stopped where the legs do not close (max |phi| above
  :data:`CLOSED` max(1, |p|): Gauss-Newton's steps also vanish at a least-squares minimum) - never a silent wrong
  answer; ``residual`` gets max |phi| there.  A jump of assembly mode is flagged by a negative count -k (the legs
  closed in k steps, s and p hold that assembly): a correction above the tolerance failed to halve the one before.
  Inside the Newton-Kantorovich region of the start (h <= 1/2; Ortega and Rheinboldt, Iterative Solution of
  Nonlinear Equations in Several Variables, 12.6.2) the corrections are bounded by the majorant's, which at least
  halve, and the iterates converge to the unique solution within 2 |first correction| of the start, the one its
  assembly mode continues to; a correction that does not halve says the start was outside that region, and the
  solution may belong to another mode;
* ``<model>_assembly_jacobian(q, s, p, params..., J)``: J = dp/dq (row-major, task x actuated) at an assembled
  (q, s, p), the p-part of the least-squares solution of [Phi_s Phi_p] (ds, dp) = -Phi_q dq; returns 1, or 0 with J
  set to NaN where the platform is not determined by the actuators (a column of Phi_p past the numerical rank of
  [Phi_s Phi_p]: a singularity of the interior kind).

A step solves the normal equations by Cholesky (a third of the work; the step's error, about kappa^2 eps of it,
only slows the convergence), and Householder QR with column pivoting where a Cholesky pivot falls to rounding
(Golub and Van Loan, Matrix Computations, 4th ed., alg. 5.4.1; the column norms downdated as LAPACK's xLAQP2
does); J takes the QR (its error eps kappa), unpivoted unless a column is dependent.  The numerical rank ends at a
remaining column's norm of m eps times the largest column's; columns past it (a passive motion the closure leaves
idle, as a rod spinning between two spherical joints) get 0, the basic solution.  No allocation; the arrays have the model's
sizes.  Parameters: the union of the two functions' free parameters, in the model's order.
"""

from __future__ import annotations

from typing import Any

#: The legs close where every closure row is below this times the pose's scale (m): the run-time's rule,
#: :data:`symkin.mechanism.closure.CLOSED`.
CLOSED = 1e-9


def assembly_context(functions: list[dict[str, Any]], model_name: str) -> dict[str, Any] | None:
    """The template's ``assembly`` context, or None where the C code lacks ``closure`` or ``closure_jacobians``."""
    by_name = {f["name"]: f for f in functions if f["real"] == "double"}
    closure, jacobians = by_name.get("closure"), by_name.get("closure_jacobians")
    if closure is None or jacobians is None:
        return None
    sizes = {v["name"]: v["size"] for v in closure["vectors"]}
    blocks = {o["name"]: o for o in jacobians["outputs"]}
    rows = closure["outputs"][0]["size"]
    order = [p["name"] for p in closure["params"]] + [p["name"] for p in jacobians["params"]
                                                     if p["name"] not in {c["name"] for c in closure["params"]}]
    return {
        "prefix": model_name,
        "closed": repr(CLOSED),
        "assemble": f"{model_name}_assemble",
        "jacobian": f"{model_name}_assembly_jacobian",
        "closure": closure["symbol"],
        "closure_jacobians": jacobians["symbol"],
        "closure_params": [p["name"] for p in closure["params"]],
        "jacobian_params": [p["name"] for p in jacobians["params"]],
        "jacobian_outputs": [o["name"] for o in jacobians["outputs"]],
        "params": order,
        "rows": rows, "n": sizes["q"], "ns": sizes["s"], "np": sizes["p"],
        "unknowns": sizes["s"] + sizes["p"],
        "blocks": {name: blocks[name]["size"] for name in ("Phi_p", "Phi_q", "Phi_s")},
    }

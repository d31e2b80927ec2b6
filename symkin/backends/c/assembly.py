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
  [Phi_s Phi_p]: a singularity of the interior kind);
* ``<model>_actuated_dynamics(q, s, p, qd, params..., M, bias, W, drift, u)`` where the C code also holds
  ``closure_dynamics``: the dynamics in the actuated coordinates at an assembled (q, s, p) moving at qd - the
  projection of :mod:`symkin.runtime.closure_dynamics` (W = [1; -A^+ Phi_q], c = [0; -A^+ gamma], M = W^T M_z W,
  bias = W^T (M_z c + h_z)) with A^+ applied as the least-squares solution by Householder QR (leg by leg, else of
  the whole system unpivoted); returns 0 with NaN where a column of A = [Phi_s Phi_p] is dependent (no unique
  projection: the run-time's pseudo-inverse decides there).  Its parameters: closure_jacobians', then
  closure_dynamics' others;
* ``<model>_assemble_inverse(p, q, s, params..., max_iterations, tolerance, max_step, stall, residual)`` and its
  ``_batch``: Gauss-Newton for the actuated and passive joints (q, s) at a platform pose p, by
  :func:`symkin.newton.newton_iterate`'s rules (a step longer than ``max_step`` shortened to it, a residual that has
  not fallen below :data:`symkin.newton.STALL_DECREASE` times its value ``stall`` steps before given up) - the
  continuation of a workspace (:mod:`symkin.mechanism.continuation`) takes its batches of solves from it.  The legs
  decouple entirely there ([Phi_q Phi_s] is block diagonal over them): each step is the Householder QR solution of
  each leg's block, the pivoted dense QR where a block has a dependent column.

The legs make the system sparse: Phi_s is block diagonal over the legs (each leg's closure rows hold only its own
passive joints; :func:`leg_blocks` finds the blocks from the structural zeros of the generated ``closure_jacobians``).
A step and J solve it leg by leg: each leg's rows are turned by the Householder QR of its block of Phi_s, which
leaves the leg's passive joints to a triangle and a few reduced rows in p alone; those of every leg, with the rows
no passive joint enters, give p by a small QR (the orthogonal transformation keeps the QR's error, eps kappa, at
the cost of the legs' small blocks).  Where a leg's block or the reduced rows have a dependent column, or the model
has no such blocks, the dense system takes Householder QR with column pivoting (Golub and Van Loan, Matrix
Computations, 4th ed., alg. 5.4.1; the column norms downdated as LAPACK's xLAQP2 does), unpivoted for J unless a
column is dependent.  The numerical rank ends at a remaining column's norm of m eps times the largest column's;
columns past it (a passive motion the closure leaves idle, as a rod spinning between two spherical joints) get 0,
the basic solution.  No allocation; the arrays have the model's sizes.  Parameters: the union of the two
functions' free parameters, in the model's order.
"""

from __future__ import annotations

from typing import Any

from symkin.newton import STALL_DECREASE

#: The legs close where every closure row is below this times the pose's scale (m): the run-time's rule,
#: :data:`symkin.mechanism.closure.CLOSED`.
CLOSED = 1e-9
#: The longest stall test (steps looked back on) of the generated inverse: its ring of residuals has this many + 1.
STALL_MOST = 32


def leg_blocks(zero: list[bool], rows: int, ns: int) -> tuple[list[dict[str, list[int]]], list[int]] | None:
    """The closure's rows and passive joints split into legs: the connected blocks of Phi_s's structural non-zeros
    (``zero``: its row-major entries that are 0 whatever the inputs), each rows x columns with at least as many rows
    as columns, and the rows no passive joint enters (the platform's own constraints).  None where a block has fewer
    rows than columns (its passive joints are not determined by its rows alone: the dense solve takes it)."""
    parent = list(range(rows + ns))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    for i in range(rows):
        for j in range(ns):
            if not zero[i * ns + j]:
                parent[root(i)] = root(rows + j)
    members: dict[int, dict[str, list[int]]] = {}
    for k in range(rows + ns):
        block = members.setdefault(root(k), {"rows": [], "columns": []})
        block["rows" if k < rows else "columns"].append(k if k < rows else k - rows)
    legs = sorted((b for b in members.values() if b["columns"]), key=lambda b: b["columns"][0])
    free = sorted(r for b in members.values() if not b["columns"] for r in b["rows"])
    if any(len(b["rows"]) < len(b["columns"]) for b in legs):
        return None
    return legs, free


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
    n, ns, np_ = sizes["q"], sizes["s"], sizes["p"]
    split = leg_blocks([a["zero"] for a in blocks["Phi_s"]["assignments"]], rows, ns)
    legs, free = split if split is not None else ([], [])
    reduced = sum(len(b["rows"]) - len(b["columns"]) for b in legs) + len(free)
    if reduced < np_:   # the legs' reduced rows cannot determine the pose: the dense QR takes every step
        legs, free = [], []
    zero_q = [a["zero"] for a in blocks["Phi_q"]["assignments"]]
    zero_s = [a["zero"] for a in blocks["Phi_s"]["assignments"]]
    inverse_split = leg_blocks([flag for i in range(rows) for flag in zero_q[i * n:(i + 1) * n] + zero_s[i * ns:(i + 1) * ns]],
                               rows, n + ns)
    right_sides = max(1, n)     # a step's one, J's n
    placed, cells, rows_before, reduced_before = [], 0, 0, 0
    for block in legs:      # where each leg's rows go: its storage (cells and rows before it) and its reduced rows
        m, nc = len(block["rows"]), len(block["columns"])
        placed.append(block | {"cells_before": cells, "rows_before": rows_before, "reduced_before": reduced_before})
        cells, rows_before, reduced_before = cells + m * nc, rows_before + m, reduced_before + m - nc
    return {
        "dynamics": _dynamics_context(by_name.get("closure_dynamics"), [p["name"] for p in jacobians["params"]],
                                      model_name, rows, n + ns + np_),
        "legs": placed, "free_rows": free, "reduced_rows": reduced, "right_sides": right_sides,
        "free_before": reduced_before,
        "leg_storage": cells + rows_before * (np_ + right_sides),
        "prefix": model_name,
        "closed": repr(CLOSED),
        "assemble": f"{model_name}_assemble",
        "jacobian": f"{model_name}_assembly_jacobian",
        "inverse": f"{model_name}_assemble_inverse",
        "inverse_legs": inverse_split[0] if inverse_split is not None else [],
        "inverse_unknowns": n + ns, "most_unknowns": max(n + ns, ns + np_),
        "stall_most": STALL_MOST, "stall_decrease": repr(STALL_DECREASE),
        "closure": closure["symbol"],
        "closure_jacobians": jacobians["symbol"],
        "closure_params": [p["name"] for p in closure["params"]],
        "jacobian_params": [p["name"] for p in jacobians["params"]],
        "jacobian_outputs": [o["name"] for o in jacobians["outputs"]],
        "params": order,
        "rows": rows, "n": n, "ns": ns, "np": np_, "unknowns": ns + np_,
        "blocks": {name: blocks[name]["size"] for name in ("Phi_p", "Phi_q", "Phi_s")},
    }


#: closure_dynamics' vector inputs and outputs, in order, as :mod:`symkin.parallel.closure_dynamics` emits them.
DYNAMICS_INPUTS, DYNAMICS_OUTPUTS = ("q", "s", "p", "qd", "sd", "pd"), ("M_z", "h_z", "gamma", "u")


def _dynamics_context(dynamics: dict[str, Any] | None, jacobian_params: list[str], model_name: str, rows: int,
                      variables: int) -> dict[str, Any] | None:
    """The template's ``assembly.dynamics``: ``<model>_actuated_dynamics``, the dynamics in the actuated coordinates
    from the generated closure_jacobians and closure_dynamics (:mod:`symkin.runtime.closure_dynamics`'s projection,
    in C); None where the C code has no closure_dynamics of the expected form.  Its parameters: closure_jacobians',
    then closure_dynamics' others."""
    if dynamics is None or [v["name"] for v in dynamics["vectors"]] != list(DYNAMICS_INPUTS) \
            or [o["name"] for o in dynamics["outputs"]] != list(DYNAMICS_OUTPUTS):
        return None
    sizes = {o["name"]: o["size"] for o in dynamics["outputs"]}
    if sizes != {"M_z": variables * variables, "h_z": variables, "gamma": rows, "u": 1}:
        return None
    own = [p["name"] for p in dynamics["params"]]
    return {"name": f"{model_name}_actuated_dynamics", "closure_dynamics": dynamics["symbol"], "own_params": own,
            "params": jacobian_params + [name for name in own if name not in jacobian_params], "variables": variables}

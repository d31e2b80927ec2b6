"""``symkin ik``: inverse kinematics of a serial model for one or more targets."""

from __future__ import annotations

import argparse
import json
import math
from typing import TYPE_CHECKING, Any

from symkin.cli.progress import Progress
from symkin.errors import ModelError, Problem

if TYPE_CHECKING:
    import numpy as np

    from symkin.runtime import LoadedModel

#: Outputs the solvers use; task_coordinates only where the task space has coordinates.
IK_OUTPUTS = ("fk", "jacobian_geometric", "jacobian", "task_coordinates")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ik", help="inverse kinematics: joint coordinates for target poses",
        description="Solve the inverse kinematics of a serial model. With a closed form (planar 2R, the UR "
                    "family) every solution branch is listed with its singularity flags; otherwise damped least "
                    "squares runs from --q0 (or from --starts random configurations) and reports convergence. "
                    "Exit code 0 if every target has a solution within the joint limits, 1 if one has none.",
        epilog="Targets: a pose is 6 numbers 'x y z rx ry rz' (position and rotation vector, as UR controllers "
               "write it) or 16 numbers (the 4x4 base_T_tcp, row by row); a task-space target has one number per "
               "task-space component of the model (e.g. 'x y' for planar_2r). Example: "
               "symkin ik models/ur10e.yaml --target 0.5 0.2 0.4 0 3.14159 0")
    p.add_argument("model", metavar="MODEL",
                   help="a model file (YAML; the needed functions are derived on the fly) or a directory "
                        "written by 'symkin derive' (e.g. generated/ur10e)")
    p.add_argument("--target", "-t", nargs="+", type=float, action="append", required=True, metavar="V",
                   help="target values (repeat --target for several targets)")
    p.add_argument("--kind", choices=("pose", "task"),
                   help="target kind (default: pose if the model's task space is the pose, else task)")
    p.add_argument("--method", choices=("auto", "closed-form", "numeric"), default="auto",
                   help="auto: the closed form when the model's structure has one, else numeric (default)")
    p.add_argument("--q0", nargs="+", type=float, metavar="Q",
                   help="start configuration of the numeric solver (default: zero within the limits)")
    p.add_argument("--starts", type=int, default=0, metavar="K",
                   help="numeric: solve from K random starts within the limits and list the distinct solutions")
    p.add_argument("--tolerance", type=float, default=1e-13,
                   help="numeric convergence tolerance, relative to max(1, |target position|) (default: %(default)g)")
    p.add_argument("--max-iterations", type=int, default=200, help="numeric iteration limit (default: 200)")
    p.add_argument("--degrees", action="store_true", help="print revolute angles in degrees")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.set_defaults(run=run)


def _loaded(path: str) -> LoadedModel:
    """The generated code of ``path``: a derived directory as is, a model file derived on the fly (the outputs of
    :data:`IK_OUTPUTS` it has, through the derivation cache)."""
    from symkin.analysis import model_files

    return model_files.generated_model(path, "numpy", outputs=(), optional=IK_OUTPUTS, display=Progress)


def _bad_argument(option: str, message: str, fix: str) -> ModelError:
    """A bad command-line argument: exit code 2, like a bad model file."""
    return ModelError([Problem("<command line>", None, None, option, message, fix)])


def _target(values: list[float], kind: str, kin) -> np.ndarray:
    import numpy as np

    from symkin.ik.rotations import pose_from_vector

    if kind == "pose":
        if len(values) == 6:
            return pose_from_vector(np.array(values))
        if len(values) == 16:
            return np.array(values).reshape(4, 4)
        raise _bad_argument("--target", f"a pose target has 6 values or 16, got {len(values)}",
                            "write x y z rx ry rz (position, rotation vector) or the 16 entries of the 4x4 pose")
    if len(values) != len(kin.task_space):
        raise _bad_argument("--target", f"a task-space target of {kin.name} has {len(kin.task_space)} values, "
                                       f"got {len(values)}", f"write the values of {' '.join(kin.task_space)}")
    return np.array(values)


def _angles(q, kin, degrees: bool) -> list[float]:
    return [math.degrees(v) if degrees and r else float(v) for v, r in zip(q, kin.revolute)]


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from symkin.ik import ModelKinematics, closed_form_solver, numeric_branches, solve_numeric
    from symkin.ik.closed_form import BranchFlag

    model = _loaded(args.model)
    kin = ModelKinematics(model)
    kind = args.kind or kin.default_kind
    solver = closed_form_solver(kin) if args.method != "numeric" else None
    if solver is not None and solver.kind != kind:
        solver = None
    if args.method == "closed-form" and solver is None:
        raise _bad_argument("--method", f"no closed form is known for the structure of {kin.name} with "
                                       f"{kind} targets", "use --method numeric (or auto)")
    if args.q0 is not None and len(args.q0) != kin.dof:
        raise _bad_argument("--q0", f"{kin.name} has {kin.dof} joints, got {len(args.q0)} values",
                            f"give {kin.dof} values: {' '.join(kin.coordinates)}")
    unit = "deg" if args.degrees else "rad"
    targets: list[dict[str, Any]] = []
    report: dict[str, Any] = {"model": kin.name, "kind": kind, "coordinates": list(kin.coordinates), "angle_unit": unit,
              "targets": targets}
    for values in args.target:
        target = _target(values, kind, kin)
        entry: dict = {"target": values, "solutions": []}
        if solver is not None:
            found = solver.solve(target)
            entry["method"] = f"closed form ({solver.name})"
            for k, branch in enumerate(found.branches):
                entry["solutions"].append({
                    "branch": branch, "valid": bool(found.valid[k]),
                    "within_limits": bool(found.within_limits[k]),
                    "flags": BranchFlag.describe(int(found.flags[k])),
                    "q": _angles(found.q[k], kin, args.degrees) if found.valid[k] else None,
                    "position_error": float(found.position_error[k]) if found.valid[k] else None,
                    "orientation_error": float(found.orientation_error[k]) if found.valid[k] else None})
            entry["solved"] = bool(found.reachable)
        elif args.starts > 0:
            distinct, result = numeric_branches(kin, target, starts=args.starts, kind=kind,
                                                tolerance=args.tolerance, max_iterations=args.max_iterations)
            entry["method"] = f"damped least squares from {args.starts} random starts"
            entry["converged_starts"] = int(result.converged.sum())
            for q in distinct:
                entry["solutions"].append({"q": _angles(q, kin, args.degrees), "valid": True,
                                           "within_limits": True})
            entry["solved"] = len(distinct) > 0
        else:
            q0 = np.zeros(kin.dof) if args.q0 is None else np.array(args.q0)
            result = solve_numeric(kin, target, q0, kind=kind, tolerance=args.tolerance,
                                   max_iterations=args.max_iterations)
            entry["method"] = "damped least squares"
            entry["solutions"].append({
                "q": _angles(result.q, kin, args.degrees), "valid": bool(result.converged),
                "within_limits": True, "reason": str(result.reason), "iterations": int(result.iterations),
                "position_error": float(result.position_error),
                "orientation_error": float(result.orientation_error)})
            entry["solved"] = bool(result.converged)
        targets.append(entry)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        _print_report(report)
    return 0 if all(t["solved"] for t in report["targets"]) else 1


def _print_report(report: dict) -> None:
    print(f"{report['model']}: {report['kind']} targets; q = [{', '.join(report['coordinates'])}] "
          f"({report['angle_unit']} for revolute joints)")
    for i, entry in enumerate(report["targets"]):
        print(f"target {i + 1} [{' '.join(f'{v:g}' for v in entry['target'])}]: {entry['method']}")
        if "converged_starts" in entry:
            print(f"  {entry['converged_starts']} starts converged, {len(entry['solutions'])} distinct solutions")
        for s in entry["solutions"]:
            label = f"  {s['branch']}: " if "branch" in s else "  "
            if s["q"] is None:
                print(f"{label}no solution ({s['flags']})")
                continue
            q = ", ".join(f"{v:.10g}" for v in s["q"])
            notes = [s["flags"]] if "flags" in s else []
            if "reason" in s:
                notes.append(f"{s['reason']} after {s['iterations']} iterations")
            if not s["within_limits"]:
                notes.append("outside the joint limits")
            if s.get("position_error") is not None:
                notes.append(f"residual {s['position_error']:.2g}, {s['orientation_error']:.2g} rad")
            print(f"{label}q = [{q}]" + (f" ({'; '.join(notes)})" if notes else ""))
        if not entry["solved"]:
            print("  no solution: the target is unreachable within the joint limits"
                  + (" (or the numeric solver did not converge; try --starts)" if "branch" not in
                     (entry["solutions"] or [{}])[0] else ""))

"""``symkin mobility`` and ``symkin topologies``: structural analysis (seed sec. 2.2, eqs. 8.1-8.4)."""

from __future__ import annotations

import argparse
import json
import sys

from symkin.text_table import format_table


def register_mobility(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("mobility", help="mobility (Gruebler-Kutzbach-Chebychev) of model files",
                       description="Count bodies, joints and joint DoF of each model and print its mobility "
                                   "F = lambda (n - g - 1) + sum f_i - f_id + s (seed eq. 8.2), its degree of "
                                   "parallelism P_g = k / F (eq. 8.1) and the joint-DoF budget F + 6 (k - 1) "
                                   "(eq. 8.4); for a parallel model with a home pose, whether its legs let the "
                                   "platform move in exactly the declared coordinates there (the intersection of "
                                   "the legs' joint twists, actuators free and locked). Exit code 1 if a model's "
                                   "mobility differs from the DoF it is built for (its task coordinates or joints), "
                                   "2 if its legs do not constrain the platform to parallel.motion.")
    p.add_argument("models", nargs="+", metavar="MODEL", help="model file(s) (YAML)")
    p.add_argument("--json", action="store_true", help="print one JSON object per model instead of text")
    p.set_defaults(run=run_mobility)


def run_mobility(args: argparse.Namespace) -> int:
    from symkin import pipeline
    from symkin.model import load_model
    from symkin.structure.mobility import model_mobility, parallelism_class

    status = 0
    for path in args.models:
        model = load_model(path)
        r = model_mobility(model)
        if r.mobility != r.intended:
            status = max(status, 1)
        motion = pipeline.platform_motion(model)
        if motion is not None and motion.problems:
            status = 2
            for problem in motion.problems:
                print(f"{path}: parallel.motion: {problem}", file=sys.stderr)
        if args.json:
            record = {"model": r.model, "mechanism": r.mechanism, "lambda": r.lam, "bodies": r.bodies,
                      "joints": r.joints, "joint_dof": sum(r.joint_dofs), "identical": r.identical,
                      "constraints": r.constraints, "mobility": r.mobility, "intended": r.intended,
                      "legs": r.legs, "parallelism": str(r.parallelism), "budget": r.budget}
            if motion is not None:
                record["home_motion"] = {"free": motion.free, "locked": motion.locked,
                                         "problems": list(motion.problems), "note": motion.note}
            print(json.dumps(record))
            continue
        if model.parallel is not None:
            legs = " ".join("".join(j.type.value for j in leg.joints) for leg in model.parallel.legs)
            kind = f"parallel, {r.legs} legs: {legs}"
        else:
            kind = f"serial chain of {r.joints} joints"
        verdict = "as intended" if r.mobility == r.intended else f"NOT the intended {r.intended}"
        print(f"{path}: {model.name} ({kind})")
        print(f"  F = {r.lam} ({r.bodies} - {r.joints} - 1) + {sum(r.joint_dofs)} - {r.identical} + {r.constraints} "
              f"= {r.mobility}  (eq. 8.2: lambda, n bodies, g joints, sum f_i, f_id, s); {verdict}")
        if r.mechanism == "parallel" and r.mobility > 0:
            print(f"  P_g = k / F = {r.legs}/{r.mobility} = {r.parallelism}: {parallelism_class(r.parallelism)}  "
                  "(eq. 8.1)")
        print(f"  joint-DoF budget F + {r.lam} (k - 1) = {r.budget}, the model has {sum(r.joint_dofs)}  (eq. 8.4)")
        if motion is not None:
            print(f"  at the home pose: {_motion_text(model, motion)}")
    return status


def _motion_text(model, motion) -> str:
    """The home pose's check of the platform motion, in one line."""
    if motion.note:
        return motion.note
    declared = f"[{', '.join(model.task_space)}]"
    if motion.problems:
        return f"the legs do not constrain the platform to {declared} (see the errors above)"
    return (f"the legs let the platform move in {declared} ({motion.free} DoF) with the actuators free, and hold it "
            "with them locked: as declared")


def register_topologies(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("topologies", help="enumerate and reduce symmetric parallel topologies (seed sec. 2.2.2)",
                       description="Enumerate every leg topology (R, P, U, C, S joints, base to platform) of a "
                                   "symmetric F-DoF, k-leg spatial mechanism with the joint DoF of eq. (8.4) "
                                   "split evenly (Table 8.1), then eliminate by the criteria of sec. 2.2.2 - "
                                   "functionality as a TPM (Carricato), position of actuators, number of "
                                   "joints - and print each eliminated topology with the criterion that "
                                   "removed it (Table 8.2) and the survivors. The seed's tables are missing; "
                                   "this is a reconstruction from its text.")
    p.add_argument("--dof", type=int, default=3, help="degrees of freedom F of the mechanism (default: %(default)s)")
    p.add_argument("--legs", type=int, default=3, help="number of legs k (default: %(default)s)")
    p.add_argument("--motion", choices=("auto", "translation", "general"), default="auto",
                   help="translation applies the TPM criteria (default auto: translation when F = 3)")
    p.add_argument("--joints", default="RPUCS", help="joint letters legs are built from (default: %(default)s)")
    p.add_argument("--summary", action="store_true", help="count the eliminations instead of listing them")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(run=run_topologies)


def run_topologies(args: argparse.Namespace) -> int:
    from symkin.errors import SymkinError
    from symkin.structure.mobility import degree_of_parallelism, parallelism_class
    from symkin.structure.synthesis import CRITERION, synthesize

    translational = None if args.motion == "auto" else args.motion == "translation"
    try:
        result = synthesize(args.dof, args.legs, translational, args.joints.upper())
    except ValueError as err:
        raise SymkinError(str(err)) from None
    if args.json:
        print(json.dumps({
            "dof": result.dof, "legs": result.legs, "leg_dof": result.leg_dof, "budget": result.budget,
            "translational": result.translational, "survivors": list(result.survivors),
            "eliminated": [{"topology": v.topology, "distribution": v.distribution, "criterion": v.criterion.key,
                            "group": v.criterion.group, "reason": v.detail} for v in result.eliminated],
        }, indent=2))
        return 0
    pg = degree_of_parallelism(result.legs, result.dof)
    print(f"F = {result.dof}, k = {result.legs}: P_g = {pg} ({parallelism_class(pg)}, eq. 8.1); "
          f"sum f_i = F + 6 (k - 1) = {result.budget} (eq. 8.4), {result.leg_dof} per leg; "
          f"{'TPM criteria applied' if result.translational else 'general motion'}")
    groups: dict[str, list[str]] = {}
    for v in result.verdicts:
        groups.setdefault(v.distribution, []).append(v.topology)
    print(f"\nCandidates (Table 8.1, reconstructed): {len(result.verdicts)} leg topologies")
    for distribution, names in groups.items():
        print(f"  {distribution} ({len(names)}): {' '.join(names)}")
    print(f"\nEliminated (Table 8.2, reconstructed): {len(result.eliminated)}")
    if args.summary:
        counts: dict[str, int] = {}
        for v in result.eliminated:
            counts[v.criterion.key] = counts.get(v.criterion.key, 0) + 1
        rows = [[c.group, c.rule, counts[key]] for key, c in CRITERION.items() if key in counts]
        print(format_table(["criterion", "rule", "eliminated"], rows))
    else:
        rank = {distribution: i for i, distribution in enumerate(groups)}
        ordered = sorted(result.eliminated, key=lambda v: rank[v.distribution])
        rows = [[v.distribution, v.topology, v.criterion.group, v.detail] for v in ordered]
        print(format_table(["DoF", "topology", "criterion", "reason"], rows))
    print(f"\nSurviving ({len(result.survivors)}): {', '.join(result.survivors)}")
    rotary = [t for t in result.survivors if t[0] == "R"]
    if rotary:
        print(f"With a revolute joint at the base (drivable by a rotary electric motor): {', '.join(rotary)}")
    return 0

"""``symkin optimize MODEL``: dimensioning with CasADi and IPOPT or JAX gradients and L-BFGS-B or SLSQP (seed
sec. 4 steps 1-3), rated independently."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress

#: Largest --nodes: 2^16 Sobol nodes, or 16^3 grid points of a parallel model's box.
MAX_NODES = 16
#: Where the objective's derivatives come from: the CasADi program (IPOPT) or jax.grad (L-BFGS-B, SLSQP).
GRADIENTS = ("casadi", "jax")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "optimize",
        help="dimensioning: maximize the GCI or the workspace over free parameters (CasADi + IPOPT, or JAX gradients)",
        description="Dimensioning optimization (seed sec. 4, steps 1-3): maximize a smooth surrogate of the global "
                    "conditioning index (eq. 8.28, with the Frobenius condition number 1/kappa_F at fixed sample "
                    "points) or the workspace measure over the free design parameters, with IPOPT on the "
                    "generated CasADi functions, subject to parameter bounds and a required workspace box (or, with "
                    "--gradients jax, with L-BFGS-B or SLSQP on jax.grad of the same surrogate). The "
                    "start and optimized designs are then rated independently on the generated numpy code (the "
                    "true GCI with 1/kappa from singular values, randomized QMC with a 95 % confidence "
                    "half-width; box reachability on a dense grid). Serial models integrate over the joint limits "
                    "with dW = |det J| dq; parallel models over the required box (a spherical platform's box of "
                    "orientations with the invariant measure of SO(3) and 1/kappa of its angular-velocity "
                    "Jacobian). Writes history.png, design.png and result.json into the output directory "
                    "(replaced atomically).",
    )
    analysis_args.add_model_arguments(p, backend=False)
    p.add_argument("--maximize", choices=("gci", "workspace", "force"), default="gci",
                   help="objective (default: %(default)s; workspace: serial models only; force: the isotropic force "
                        "at the worst point of the required box; a serial model's at its box configurations)")
    p.add_argument("--effort-limit", metavar="T[,T...]",
                   help="the actuators' peak efforts of --maximize force (N m or N; one value for all or one per "
                        "actuator; default: the model's effort limits)")
    p.add_argument("--max-apparent-mass", type=float, metavar="KG",
                   help="a parallel model's handle may feel at most this mass in any direction at every point of the "
                        "required box (the eigenvalues of (J M^-1 J^T)^-1; the model needs its mass_matrix)")
    p.add_argument("--free", required=True, metavar="A,B",
                   help="the parameters to optimize, e.g. --free l1 (the others keep their values)")
    p.add_argument("--bounds", action="append", default=[], metavar="NAME=LOWER:UPPER[,...]",
                   help="span of a free parameter in its unit (default: half to twice its start value); repeatable")
    p.add_argument("--require-box", metavar="x=LOWER:UPPER,y=...",
                   help="workspace box [m] that must stay reachable (all task position axes); required for a "
                        "parallel model, whose GCI is taken over it; a spherical platform's box is one of "
                        "orientations, e.g. roll=-20deg:20deg,pitch=-20deg:20deg,yaw=-20deg:20deg")
    p.add_argument("--margin", type=float, default=0.0, metavar="M",
                   help="the box is required with this clearance on every side, in its unit (m, or rad for "
                        "orientations) (default: %(default)s)")
    p.add_argument("--length", type=float, default=None, metavar="L",
                   help="characteristic length [m] of a task space mixing translations and rotations")
    analysis_args.add_orientation_argument(p)
    p.add_argument("--nodes", type=int, default=None, metavar="N",
                   help="fixed sample points of the surrogate: serial: 2^N Sobol nodes (default 8); "
                        "parallel: N per axis of the box (default 5)")
    p.add_argument("-n", "--samples", type=int, default=2**14, metavar="N",
                   help="integrand evaluations of the independent GCI (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the nodes and of the evaluation (default: 0)")
    p.add_argument("--gradients", choices=GRADIENTS, default="casadi",
                   help="casadi: IPOPT on the CasADi program, its exact derivatives (every objective and constraint); "
                        "jax: L-BFGS-B on the same surrogate with jax.grad through the generated JAX code (a serial "
                        "model's gci or workspace within the bounds, no --require-box), or SLSQP with the reach "
                        "constraints (a parallel model's gci, or its worst force in epigraph form, over --require-box, its "
                        "closed-form ik, also under --max-apparent-mass); MODEL derived with the JAX backend, or a model file; XLA compiles once, ~1-2 s, then "
                        "each iteration is one call "
                        "(default: %(default)s)")
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/optimize/<model>)")
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    from symkin import design
    from symkin.atomic import replace_directory
    from symkin.design import plots

    wall = time.perf_counter()
    try:
        free = [name.strip() for name in args.free.split(",") if name.strip()]
        bounds = analysis_args.parse_ranges(args.bounds, "--bounds")
        box = analysis_args.parse_ranges([args.require_box], "--require-box") if args.require_box else None
        values = analysis_args.parse_assignments(args.assignments)
        limits = analysis_args.parse_limits(args.limits)
        if args.nodes is not None and not 1 <= args.nodes <= MAX_NODES:
            raise ValueError(f"--nodes must be between 1 and {MAX_NODES}, got {args.nodes}")
        if args.samples < 16:
            raise ValueError(f"--samples must be at least 16, got {args.samples}")
        with Progress(Path(args.model).stem) as progress:
            progress("loading the generated code")
            # a parallel model's rating checks the working mode by its closed-form fk, where it has one
            masses = design.APPARENT_MASS_FUNCTIONS if args.max_apparent_mass is not None else ()
            numpy_model, other_model = model_files.load_models(args.model, ("numpy", args.gradients),
                                                               NEEDS["design"], ("fk", *masses), display=Progress)
            efforts = (analysis_args.per_joint("--effort-limit", args.effort_limit, len(numpy_model.info.coordinates))
                       if args.effort_limit else None)
            problem = design.design_problem(numpy_model, args.maximize, free, bounds=bounds, values=values, box=box,
                                            margin=args.margin, limits=limits, length=args.length,
                                            effort_limits=efforts, max_apparent_mass=args.max_apparent_mass,
                                            orientation=analysis_args.parse_orientation(args.orientation))
            if args.gradients == "jax":
                from symkin.design import gradient_solving

                progress("compiling the JAX surrogate (L-BFGS-B, or SLSQP with constraints)")
                solution, description = gradient_solving.solve_with_jax(problem, other_model, numpy_model,
                                                                        nodes=args.nodes, seed=args.seed)
            else:
                progress("building the CasADi program")
                start = time.perf_counter()
                program = design.formulate(problem, other_model, numpy_model, nodes=args.nodes, seed=args.seed)
                build = time.perf_counter() - start
                progress("IPOPT")
                solution = design.solve(problem, program, build_seconds=build)
                description = program.description
            if not solution.success:
                lighter = ("" if args.max_apparent_mass is None else
                           f" (or no design within them feels at most {args.max_apparent_mass:g} kg at the handle: "
                           "raise --max-apparent-mass)")
                print(f"error: {solution.solver} did not converge ({solution.status}, {solution.iterations} iterations); "
                      f"if the required box cannot be reached within the bounds{lighter}, widen --bounds or shrink "
                      "--require-box; nothing was written", file=sys.stderr, flush=True)
                return 1
            progress("independent evaluation")
            start = time.perf_counter()
            rating = (design.evaluate(problem, numpy_model, solution.start, samples=args.samples, seed=args.seed),
                      design.evaluate(problem, numpy_model, solution.optimum, samples=args.samples, seed=args.seed,
                                      box_points=solution.box_points,
                                      box_configurations=solution.box_configurations))
            evaluation = time.perf_counter() - start
            progress("drawing")
            files: dict[str, str | bytes] = {
                "history.png": plots.png(plots.history_figure(solution, problem, numpy_model.name)),
                "design.png": plots.png(plots.design_figure(problem, numpy_model, solution, rating)),
            }
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    wall = time.perf_counter() - wall
    seconds = {"build": solution.build_seconds, "solve": solution.solve_seconds, "evaluation": evaluation,
               "wall": wall}
    report = _report(args, problem, description, solution, rating, seconds)
    flat = design.scale_invariance(problem, numpy_model)
    if flat:
        report["notes"] = [f"the GCI does not change when {', '.join(flat)} scale together (J scales with them): every "
                           "design on the ray through this optimum is as good, only their ratios were optimized; "
                           f"keep one of them out of --free to choose the scale"]
    files["result.json"] = json.dumps(report, indent=2) + "\n"
    out = Path(args.out or Path("out") / "optimize" / numpy_model.name)
    replace_directory(out, files)
    _print(report, out)
    return 0


def _report(args, problem, description: str, solution, rating, seconds: dict[str, float]) -> dict:
    before, after = rating
    return {
        "model": args.model,
        "objective": problem.objective,
        "surrogate": description,
        "parameters": {p.name: {"start": p.start, "optimum": solution.optimum[p.name], "bounds": [p.lower, p.upper]}
                       for p in problem.free},
        "surrogate_value": {"start": solution.surrogate_start, "optimum": solution.surrogate_optimum},
        "solver": {"name": solution.solver, "status": solution.status, "iterations": solution.iterations,
                  "constraint_violation": solution.constraint_violation, "history": solution.history.tolist()},
        "evaluation": {"method": before.description, "box_check": after.box_check, **{
            which: {"gci": r.gci.value, "gci_error": r.gci.error, "measure": r.measure.value,
                    "measure_error": r.measure.error, "box_reachable": r.box_reachable, "force": r.force,
                    "apparent_mass": r.apparent_mass}
            for which, r in (("start", before), ("optimum", after))}},
        "required_box": None if problem.box is None else {"lower": problem.box[0].tolist(),
                                                          "upper": problem.box[1].tolist(),
                                                          "margin": problem.margin,
                                                          "orientation": None if problem.orientation is None
                                                          else problem.orientation.tolist()},
        "seconds": seconds,
    }


def _print(report: dict, out: Path) -> None:
    print(f"{report['model']}: maximize {report['objective']}; {report['surrogate']}")
    for note in report.get("notes", ()):
        print(f"  note: {note}")
    for name, p in report["parameters"].items():
        print(f"  {name}: {p['start']:.6g} -> {p['optimum']:.10g}   (bounds {p['bounds'][0]:g} .. {p['bounds'][1]:g})")
    s, solver = report["surrogate_value"], report["solver"]
    print(f"  surrogate: {s['start']:.6g} -> {s['optimum']:.6g}   {solver['name']}: {solver['status']}, "
          f"{solver['iterations']} iterations")
    ev = report["evaluation"]
    for which in ("start", "optimum"):
        r = ev[which]
        box = "" if r["box_reachable"] is None else f", box reachable at {100 * r['box_reachable']:.1f} % of the points"
        force = "" if r["force"] is None else f"; isotropic force at the worst box point {r['force']:.6g} N"
        mass = "" if r["apparent_mass"] is None else f"; largest apparent mass in the box {r['apparent_mass']:.6g} kg"
        print(f"  GCI ({which}): {r['gci']:.6g} +- {r['gci_error']:.2g}; measure {r['measure']:.6g} +- "
              f"{r['measure_error']:.2g}{box}{force}{mass}")
    print(f"  independent evaluation: {ev['method']}; box: {ev['box_check']}")
    t = report["seconds"]
    print(f"  time: build {t['build']:.2f} s, {solver['name']} {t['solve']:.3f} s, evaluation {t['evaluation']:.2f} s, "
          f"wall {t['wall']:.2f} s")
    print(f"  wrote {out}/history.png, design.png, result.json")

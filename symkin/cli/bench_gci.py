"""``symkin bench gci MODEL``: wall time against achieved error of every GCI integrator."""

from __future__ import annotations

import argparse
import functools
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress
from symkin.text_table import format_table

if TYPE_CHECKING:
    from symkin.analysis.convergence import Trial


def register(kinds: argparse._SubParsersAction) -> None:
    p = kinds.add_parser(
        "gci", help="GCI: run time against error of each integrator",
        description="Run every GCI integrator (grid, mc, qmc, adaptive) at a ladder of budgets on the joint domain "
                    "(dW = |det J| dq) and, where a closed-form inverse kinematics exists, on the Cartesian domain; "
                    "print wall time, estimate, estimated and achieved error against a high-accuracy reference "
                    "(adaptive cubature at rtol 1e-13), and plot time against error.")
    analysis_args.add_model_arguments(p)
    p.add_argument("--methods", metavar="NAMES",
                   help="comma-separated integrators (default: all: grid, mc, qmc, adaptive)")
    p.add_argument("--budgets", metavar="N,N,...",
                   help="integrand evaluations per run (default: 4^4 ... 4^10, i.e. 256 to 1048576)")
    p.add_argument("--domains", default="auto", metavar="NAMES",
                   help="joint and/or cartesian (default: both where an inverse kinematics exists)")
    p.add_argument("--backends", metavar="NAMES",
                   help="comma-separated generated code to time, e.g. numpy,c (default: --backend if given, "
                        "else numpy and c where emitted)")
    p.add_argument("--repeats", type=int, default=3, help="timed runs per point, the fastest kept (default: 3)")
    p.add_argument("--seed", type=int, default=0, help="seed of mc/qmc (default: %(default)s)")
    analysis_args.add_length_argument(p)
    p.add_argument("-o", "--out", metavar="FIGURE", type=analysis_args.figure_path,
                   help="plot of time against error (default: bench-results/MODEL_NAME-gci-time-vs-error.png)")
    p.set_defaults(run=run, parser=p, backend=None)


def _backend_progress(progress: Callable[[str], None], backend: str, text: str) -> None:
    progress(f"{backend}: {text}")


def _fastest_text(trial: Trial | None) -> str:
    """'1.23 ms (4096)': the time and evaluations of the fastest run within a target, or '-'."""
    return f"{trial.seconds * 1e3:.2f} ms ({trial.evaluations})" if trial is not None else "-"


def run(args: argparse.Namespace) -> int:
    from symkin.analysis import convergence, inverse, plots
    from symkin.integration.integrators import INTEGRATORS

    try:
        backends = _backends(args)
        models, limits = analysis_args.models_from_args(args, backends)
        model = models[-1]
        methods = [m.strip() for m in args.methods.split(",") if m.strip()] if args.methods else list(INTEGRATORS)
        unknown = sorted(set(methods) - set(INTEGRATORS))
        if unknown:
            raise ValueError(f"unknown integrators {unknown}; choose from {', '.join(INTEGRATORS)}")
        budgets = ([int(b) for b in args.budgets.split(",") if b.strip()] if args.budgets
                   else list(convergence.DEFAULT_BUDGETS))
        length = analysis_args.resolve_length(model, args.length, limits)
        ik = inverse.inverse_kinematics_for(model)
        domains = ["joint", "cartesian"] if args.domains == "auto" else [d.strip() for d in args.domains.split(",")]
        if args.domains == "auto" and ik is None:
            domains = ["joint"]
        if "cartesian" in domains and ik is None:
            raise ValueError(f"{model.name}: no inverse kinematics for the Cartesian domain")
        with Progress(f"bench gci {model.name}") as progress:
            progress("reference")
            # The reference does not depend on the backend; it is computed with the last one.
            reference = convergence.reference_gci(models[-1], limits=limits, length=length)
            trials = []
            for model in models:
                trials += convergence.time_against_error(
                    model, reference, methods=methods, budgets=budgets, domains=domains, repeats=args.repeats,
                    seed=args.seed, progress=functools.partial(_backend_progress, progress, model.backend), limits=limits,
                    length=length, inverse=inverse.inverse_kinematics_for(model) if ik is not None else None)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    print(f"{model.name}: GCI reference {reference} (adaptive, {reference.evaluations} evaluations, "
          f"{models[-1].backend} backend)")
    rows = [[t.domain, t.method, t.backend, t.evaluations, f"{t.seconds * 1e3:.2f}", f"{t.estimate.value:.10f}",
             f"{t.estimate.error:.2e}", f"{t.achieved:.2e}", "yes" if t.bracketed else "NO"] for t in trials]
    print(format_table(["domain", "method", "backend", "evaluations", "time ms", "GCI", "est. error", "achieved",
                        "bracketed"], rows))
    print("fastest run reaching a relative error of the GCI of:")
    targets = (1e-3, 1e-6, 1e-9)
    best = [convergence.fastest_within(trials, target) for target in targets]
    summary = [[key[1], key[2], key[0]] + [_fastest_text(b[key]) for b in best]
               for key in best[0]]  # key = (backend, domain, method)
    print(format_table(["domain", "method", "backend"] + [f"{t:g}" for t in targets], summary))
    panels: dict = {}
    for t in trials:
        name = t.method if len(models) == 1 else f"{t.method} ({t.backend})"
        times, achieved, estimated = panels.setdefault(f"{t.domain} domain", {}).setdefault(name, ([], [], []))
        times.append(t.seconds)
        achieved.append(t.achieved)
        estimated.append(t.estimate.error)
    path = plots.plot_time_against_error(panels, args.out or f"bench-results/{model.name}-gci-time-vs-error.png",
                                         title=f"GCI of {model.name}: wall time against error "
                                               f"({', '.join(m.backend for m in models)})")
    print(f"figure: {path}")
    return 0


#: Backends timed by default, where the model was emitted with them.
DEFAULT_BACKENDS = ("numpy", "c")


def _backends(args: argparse.Namespace) -> list[str]:
    """--backends, else --backend, else numpy and c where the model directory has them."""
    if args.backends:
        return [b.strip() for b in args.backends.split(",") if b.strip()]
    if args.backend:
        return [args.backend]
    if Path(args.model).suffix.lower() in model_files.MODEL_FILE_SUFFIXES:
        return ["numpy"]  # a model file is derived on the fly, for numpy
    from symkin.manifest import read_manifest
    from symkin.runtime.info import ModelInfo

    directory = Path(args.model)
    emitted = ModelInfo.from_manifest(read_manifest(directory.parent if directory.name == "manifest.json"
                                                    else directory)).backend_files
    return [b for b in DEFAULT_BACKENDS if b in emitted]

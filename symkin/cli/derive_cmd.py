"""``symkin derive``: derive models and write their generated code."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from symkin.atomic import replace_directory
from symkin.backends import BACKENDS
from symkin.cli.progress import Progress
from symkin.cli.urdf_args import ROBOT_FILE_OPTIONS, add_urdf_arguments, print_notes, urdf_options
from symkin.runtime.info import ModelInfo
from symkin.text_table import format_table


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "derive",
        help="derive models and emit code",
        description="Derive the quantities a model's scene asks for (or --only), optimize them and "
                    "write the generated code and manifest.json to OUT/<model name>/, atomically.",
    )
    p.add_argument("models", nargs="+", metavar="MODEL",
                   help="model file(s): YAML, or URDF (told by its content: a .urdf or .xml whose root is <robot>)")
    p.add_argument("-o", "--out", default="generated", metavar="OUT",
                   help="output directory (default: %(default)s)")
    p.add_argument("--only", metavar="NAMES",
                   help="comma-separated outputs to emit instead of the scene's, e.g. fk,jacobian "
                        "(see 'symkin quantities')")
    p.add_argument("--backend", metavar="NAMES",
                   help=f"comma-separated backends: {', '.join(BACKENDS)} (default: the scene's, else numpy)")
    p.add_argument("--fixed", metavar="NAMES",
                   help="comma-separated parameters to fold to their default values, or 'all' "
                        "(default: the scene's)")
    p.add_argument("--float32", action=argparse.BooleanOptionalAction, default=None,
                   help="also emit single-precision (float) C functions, suffix _f32 (default: the scene's)")
    p.add_argument("--combine", metavar="NAMES",
                   help="outputs also computed together by one function 'combined' sharing one CSE "
                        "(comma-separated, 'all' or 'none'; default: the scene's, else all)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    p.add_argument("--no-cache", action="store_true",
                   help="derive even if the derivation cache holds this model and request (and do not keep it); "
                        "see 'symkin cache list'")
    add_urdf_arguments(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from symkin import pipeline_cache

    # Validate every model and request first: a bad file writes nothing at all (a cached one was valid).
    jobs = []
    for path in args.models:
        key = pipeline_cache.request_key(path, _request(args)) if pipeline_cache.enabled() else None
        entry = None if key is None else pipeline_cache.lookup(key)
        if entry is not None and any(getattr(args, name) for name in ROBOT_FILE_OPTIONS):
            urdf_options(args, path)  # the options' own checks (robot-file options given a YAML file)
        jobs.append((path, key, entry, None if entry is not None else _validated(args, path)))
    for path, key, entry, job in jobs:
        start = time.perf_counter()
        if entry is not None:
            target = Path(args.out) / entry.model
            replace_directory(target, entry.files)
            if not args.quiet:
                print(f"{entry.model}: unchanged since a derivation kept in the cache -> {target}  "
                      f"({time.perf_counter() - start:.2f} s; --no-cache derives it again)")
                print_notes(path, entry.notes)
            continue
        from symkin import pipeline

        assert job is not None  # validated above: every job is a cache hit or a checked model and request
        model, request = job
        with Progress(model.name, enabled=not args.quiet) as progress:
            result = pipeline.generate(model, request, progress)
            target = pipeline.write(result, args.out)
        if key is not None:
            pipeline_cache.store(key, model.name, model.notes, result.files)
        if not args.quiet:
            _summary(result, target, time.perf_counter() - start)
    return 0


def _validated(args: argparse.Namespace, path: str):
    """The model of ``path`` and its request (both checked; a parallel model's legs against its declared
    ``parallel.motion`` at the home pose, as ``symkin check``)."""
    from symkin import pipeline
    from symkin.model import load_model

    model = load_model(path, **urdf_options(args, path))
    request = pipeline.resolve_request(model, args.only, args.backend, args.fixed, args.float32, args.combine)
    pipeline.require_derivable(model, request)
    return model, request


#: The options that decide what is derived: with the model file's bytes and name, the cache key.
REQUEST_OPTIONS = ("only", "backend", "fixed", "float32", "combine", *ROBOT_FILE_OPTIONS, "allow_nonphysical")


def _request(args: argparse.Namespace) -> dict[str, object]:
    """What of the command line decides the derivation (the cache key's request)."""
    return {"command": "derive", **{name: getattr(args, name) for name in REQUEST_OPTIONS}}


def _summary(result, target: Path, seconds: float) -> None:
    model = result.model
    free = sum(1 for p in model.parameters if p.name not in result.request.fixed)
    print(f"{model.name}: {model.dof} DoF, {free} free / {len(result.request.fixed)} fixed parameters "
          f"-> {target}  ({seconds:.2f} s)")
    print_notes(model.source, model.notes)
    rows = []
    for r in result.reports:
        counts = r.op_counts
        folded = f" -> {counts['folded']}" if "folded" in counts else ""
        rows.append([r.name, r.outputs, f"{counts['derived']}{folded} -> {counts['cse']}",
                     f"{r.derive_seconds:.3f}", f"{r.optimize_seconds:.3f}"])
    print(format_table(["function", "outputs", "ops derived -> cse", "derive s", "optimize s"], rows))
    emitted = ModelInfo.from_manifest(result.manifest).backend_files
    files = ", ".join(f"{b}: {_listing(list(names), 'files')}" for b, names in emitted.items())
    print(f"  emitted {files} in {result.emit_seconds:.3f} s")
    print(f"  derived {len(result.derived)} graph nodes: {_listing(result.derived, 'nodes', 12)}")


def _listing(names: list[str], noun: str, limit: int = 3) -> str:
    """The names, or the first few and a count when there are more than ``limit``."""
    if len(names) <= limit:
        return " ".join(names)
    return f"{' '.join(names[:limit])} ... ({len(names)} {noun})"

"""The one-way pipeline: model -> derivation -> optimization -> backends -> files.

:func:`generate` runs it for one model and returns a :class:`Generation` (files in
memory plus a report); :func:`write` puts the files in place atomically.  The CLI and the
tests both go through these two functions.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from symkin import manifest as manifest_io
from symkin._version import __version__
from symkin.atomic import replace_directory
from symkin.backends import BACKENDS, get_backend
from symkin.derivation import Derivation, emitted_quantities
from symkin.dynamics.feasibility import mass_matrix_problems
from symkin.errors import DerivationError, ModelError, Problem
from symkin.ir.bundle import ModelCode, ParameterInfo
from symkin.ir.spec import FunctionSpec, OptimizedFunction, combine_functions
from symkin.model.schema import Model
from symkin.optimize import optimize

if TYPE_CHECKING:  # imported where it is used: the motion check pulls the parallel derivations in
    from symkin.parallel.motion_check import MotionCheck

#: Reports a stage, and how far it is where counted: ``progress(stage, done=k, total=n)``
#: (:class:`symkin.cli.progress.Progress`).
Progress = Callable[..., None]

#: Name of the function that computes every output of a scene together (one shared CSE).
COMBINED_FUNCTION = "combined"


@dataclass(frozen=True)
class Request:
    """What to generate for a model.

    Attributes:
        outputs: quantity names, in order.
        fixed: parameters folded to their defaults.
        backends: backend names.
        float32: also emit single-precision variants (C backend).
        combine: outputs also computed together by the function ``scene`` (at least two, or none).
    """

    outputs: tuple[str, ...]
    fixed: tuple[str, ...]
    backends: tuple[str, ...]
    float32: bool = False
    combine: tuple[str, ...] = ()


@dataclass
class FunctionReport:
    """Per-function figures for the summary table."""

    name: str
    outputs: str
    op_counts: dict[str, int]
    derive_seconds: float
    optimize_seconds: float


@dataclass
class Generation:
    """The result of :func:`generate`: files to write and what happened."""

    model: Model
    request: Request
    files: dict[str, str | bytes]
    manifest: dict
    functions: list[OptimizedFunction]
    derived: list[str]
    reports: list[FunctionReport] = field(default_factory=list)
    emit_seconds: float = 0.0


def _split(value: str | Sequence[str] | None) -> tuple[str, ...] | None:
    if value is None:
        return None
    if isinstance(value, str):
        return tuple(v.strip() for v in value.split(",") if v.strip())
    return tuple(value)


def require_derivable(model: Model, request: Request) -> None:
    """What a derivation checks before any work, so that ``symkin check``, ``symkin derive`` and
    :func:`symkin.derive` refuse the same models: the inertias the request needs are physical
    (:data:`symkin.dynamics.physical.INERTIA_OUTPUTS`), and a parallel model's legs move its platform as
    ``parallel.motion`` declares at the home pose (:func:`symkin.parallel.motion_check.require_declared_motion`).

    Raises:
        ModelError: the problems, each located in the model file, with the fix.
    """
    from symkin.dynamics.physical import INERTIA_OUTPUTS
    from symkin.parallel.motion_check import require_declared_motion

    if model.nonphysical and INERTIA_OUTPUTS & set(request.outputs):
        raise ModelError(list(model.nonphysical))
    if model.parallel is not None:
        require_declared_motion(model)


def derivable_quantities() -> list[tuple[str, str, str]]:
    """(output, kind of model, summary) of every quantity a scene or ``--only`` may request, serial chains' first
    (``symkin quantities``)."""
    from symkin.derivation import registry

    defs = {(q.name, q.mechanism): q for mechanism in ("serial", "parallel")
            for q in registry(mechanism).values() if q.emitted}
    return [(q.name, q.mechanism, q.summary) for q in defs.values()]


def platform_motion(model: Model) -> MotionCheck | None:
    """How a parallel model's legs move its platform at the home pose
    (:func:`symkin.parallel.motion_check.check_platform_motion`: free and locked motions, the problems against
    ``parallel.motion``), None for a model without legs: what ``symkin mobility`` reports beside the count."""
    if model.parallel is None:
        return None
    from symkin.parallel.motion_check import check_platform_motion

    return check_platform_motion(model)


def resolve_request(model: Model, only: str | Sequence[str] | None = None,
                    backends: str | Sequence[str] | None = None,
                    fixed: str | Sequence[str] | None = None,
                    float32: bool | None = None,
                    combine: str | Sequence[str] | None = None) -> Request:
    """The request from the model's scene, overridden by explicit arguments (the CLI's flags).

    ``combine`` (or the scene's) names the outputs also fused into the function ``combined``;
    ``all`` (the default) fuses every output, ``none`` none.  Scene entries that ``only``
    leaves out are dropped; explicit names must be among the outputs.

    Raises:
        ModelError: a scene entry names no known output, backend or parameter (located in
            the model file), or an explicit argument does (located at the command line).
    """
    problems: list[Problem] = []
    known_outputs = emitted_quantities(model.mechanism)
    pnames = tuple(p.name for p in model.parameters)

    def check(names: tuple[str, ...], known: Sequence[str], what: str, scene_key: str, from_cli: bool) -> None:
        for i, name in enumerate(names):
            if name in known:
                continue
            fix = f"use one of: {', '.join(known)}" if known else f"the model has no {what}s"
            message = f"unknown {what} '{name}'"
            if what == "output" and name in emitted_quantities():
                message += f" for a {model.mechanism} mechanism (it is derived for the other kind)"
            if from_cli:
                problems.append(Problem("<command line>", None, None, scene_key, message, fix))
            else:
                problems.append(model.problem(("scene", scene_key, i), message, fix))

    outputs = _split(only)
    check(outputs or model.scene.outputs, known_outputs, "output", "outputs", outputs is not None)
    chosen_backends = _split(backends)
    check(chosen_backends or model.scene.backends, tuple(BACKENDS), "backend", "backends", chosen_backends is not None)
    fixed_names = _split(fixed)
    if fixed_names == ("all",):
        fixed_names = pnames
    check(fixed_names or (), pnames, "parameter", "fixed", fixed_names is not None)
    chosen_outputs = outputs or model.scene.outputs
    fused = _split(combine)
    scene_combine = model.scene.combine
    if fused == ("none",):
        fused = ()
    elif fused is not None and fused != ("all",):
        check(fused, chosen_outputs, "output to combine", "combine", True)
    elif fused is None and scene_combine is not None:
        check(scene_combine, model.scene.outputs, "output to combine", "combine", False)
        fused = tuple(name for name in scene_combine if name in chosen_outputs)
    else:  # "all", or neither the command line nor the scene names any
        fused = chosen_outputs
    if not problems:
        problems += _reserved_word_problems(model, chosen_backends or model.scene.backends)
        problems += mass_matrix_problems(model, chosen_outputs)
    if problems:
        raise ModelError(problems)
    return Request(outputs=chosen_outputs,
                   fixed=fixed_names if fixed_names is not None else model.scene.fixed,
                   backends=chosen_backends or model.scene.backends,
                   float32=model.scene.float32 if float32 is None else float32,
                   combine=tuple(name for name in chosen_outputs if name in fused) if len(fused) > 1 else ())


def _describe_outputs(spec: FunctionSpec) -> str:
    shown = [f"{o.name} {'x'.join(map(str, o.shape)) or 'scalar'}" for o in spec.outputs[:2]]
    more = len(spec.outputs) - len(shown)
    return ", ".join(shown) + (f" (+{more} more)" if more else "")


def _quiet(_stage: str, done: int | None = None, total: int | None = None) -> None:
    pass


def _reserved_word_problems(model: Model, backends: Sequence[str]) -> list[Problem]:
    """The model's names that a backend's code cannot take (its reserved words), located in the model file.  The
    reader refuses the shipped languages' words already; this covers every registered backend."""
    return [model.problem(path, f"'{name}' is a reserved word of the {backend} backend's code",
                          "rename it, e.g. 'theta1', 'l1' or 'link2'")
            for backend in backends for words in [get_backend(backend).reserved_words()]
            for name, path in model.declared_names.items() if name in words]


def generate(model: Model, request: Request, progress: Progress = _quiet,
             derivation: Derivation | None = None) -> Generation:
    """Derive, optimize and emit everything ``request`` asks for (files stay in memory); ``derivation``: the model's
    derivation graph where the caller has one, whose quantities derived so far are reused."""
    derivation = Derivation(model) if derivation is None else derivation
    functions: list[OptimizedFunction] = []
    specs: list[FunctionSpec] = []
    reports = []
    count = len(request.outputs) + bool(request.combine)
    for k, name in enumerate(request.outputs):
        progress(f"deriving {name}", done=k, total=count)
        start = time.perf_counter()
        (spec,) = derivation.functions([name])
        derived_at = time.perf_counter()
        progress(f"optimizing {name}", done=k, total=count)
        optimized = optimize(spec, request.fixed)
        done = time.perf_counter()
        specs.append(spec)
        functions.append(optimized)
        reports.append(FunctionReport(name, _describe_outputs(spec), optimized.op_counts,
                                      derived_at - start, done - derived_at))
    if request.combine:
        if COMBINED_FUNCTION in request.outputs:
            raise DerivationError(f"a quantity may not be called '{COMBINED_FUNCTION}': that is the name of "
                                  "the combined function of a scene")
        progress(f"optimizing {COMBINED_FUNCTION}", done=count - 1, total=count)
        start = time.perf_counter()
        combined = combine_functions(model, COMBINED_FUNCTION,
                                     [spec for name, spec in zip(request.outputs, specs) if name in request.combine])
        optimized = optimize(combined, request.fixed)
        functions.append(optimized)
        reports.append(FunctionReport(COMBINED_FUNCTION, _describe_outputs(combined), optimized.op_counts,
                                      0.0, time.perf_counter() - start))
    code = ModelCode(
        name=model.name,
        hash=model.hash,
        description=model.description,
        symkin_version=__version__,
        coordinates=tuple(j.name for j in model.coordinates),
        parameters=tuple(ParameterInfo(p.name, float(p.value), p.unit, p.doc, p.name in request.fixed)
                         for p in model.parameters),
        functions=tuple(functions),
        float32=request.float32,
    )
    files: dict[str, str | bytes] = {}
    backend_files: dict[str, list[str]] = {}
    start = time.perf_counter()
    for backend_name in request.backends:
        progress(f"emitting {backend_name} code", done=request.backends.index(backend_name),
                 total=len(request.backends))
        emitted = get_backend(backend_name).emit(code)
        overlap = set(emitted) & set(files)
        if overlap:
            raise RuntimeError(f"backend {backend_name} would overwrite {sorted(overlap)}")
        files.update(emitted)
        backend_files[backend_name] = sorted(emitted)
    manifest = manifest_io.build_manifest(model, code, list(derivation.computed), backend_files)
    files[manifest_io.MANIFEST_NAME] = manifest_io.dumps(manifest)
    return Generation(model, request, files, manifest, functions, list(derivation.computed), reports,
                          time.perf_counter() - start)


def write(result: Generation, out_dir: str | Path) -> Path:
    """Write the files of ``result`` atomically to ``out_dir/<model name>``; returns that path."""
    target = Path(out_dir) / result.model.name
    replace_directory(target, result.files)
    return target

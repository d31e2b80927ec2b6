"""MODEL as a model file: derived on the fly into a scratch directory, through the derivation cache.

The library's loading of a model for an analysis (the commands call it; it imports no CLI).  An analysis's MODEL
is a generated model directory (the output of ``symkin derive``) or a model file,
which is derived into a temporary directory: fk and jacobian; ik as well for a translational parallel
mechanism; ik and the inverse Jacobian for a platform that also rotates (``NEEDS["kinematics"]`` of
:mod:`symkin.analysis.needs`); the loop closure and its Jacobians for legs without the distance form, whose
analyses continue the closure (:data:`CLOSURE_OUTPUTS`).
A derivation is kept in the derivation cache (:mod:`symkin.pipeline_cache`), so that the next command given
the unchanged file copies it.
"""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import AbstractContextManager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symkin.mechanism import MechanismKind, parallel_kind
from symkin.analysis.needs import NEEDS

if TYPE_CHECKING:
    from symkin.model.schema import Model

#: Quantities an analysis needs from a model file derived on the fly, where it says none (a serial arm's
#: kinematics; by kind of mechanism: symkin.analysis.needs.NEEDS).
ANALYSIS_OUTPUTS = NEEDS["kinematics"][MechanismKind.SERIAL]
#: A progress display opened while a model file derives, given the model's name (the CLI's
#: symkin.cli.progress.Progress, which installs itself as the reporter of symkin.reporting); none by default.
Display = Callable[[str], AbstractContextManager[Any]]
#: Suffixes of model files (derived on the fly); anything else is a generated directory.
MODEL_FILE_SUFFIXES = (".yaml", ".yml", ".urdf", ".xml", ".xacro")
#: Also derived for a parallel model file that limits passive joints: the analyses find the
#: passive joint variables from the loop closure (symkin.mechanism.passive).
PASSIVE_LIMIT_OUTPUTS = ("closure", "closure_jacobians")
#: What the analyses of legs of any topology (no distance form, so no closed-form ik) use instead of the kind's
#: outputs (symkin.analysis.continued_workspace).
CLOSURE_OUTPUTS = ("closure", "closure_jacobians")
#: Backends whose every call is a dispatch to a device (JAX): slow for the point-by-point solves of a continued
#: closure, whose analyses take the :data:`HOST_BACKEND`'s code instead (:func:`load_for_analysis`).
DISPATCHED_BACKENDS = ("jax",)
HOST_BACKEND = "numpy"


def is_model_file(path: str | Path) -> bool:
    """True if MODEL names a model file (derived on the fly), not a generated directory."""
    return Path(path).suffix.lower() in MODEL_FILE_SUFFIXES


def generated_model(path: str, backend: str = "numpy",
               outputs: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = ANALYSIS_OUTPUTS,
               optional: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = (),
               closure: Sequence[str] | None = None, reading: Mapping[str, Any] | None = None,
               display: Display | None = None) -> Any:
    """The loaded model of MODEL: a generated directory, or a model file derived on the fly.

    Args:
        path: generated directory (or its manifest.json), or a model file (YAML, or URDF with its default tip).
        backend: the backend to load (and, for a model file, to emit).
        outputs: the quantities to derive from a model file.
        optional: quantities also derived where the model has them (e.g. ``friction``, ``gravity_vector``),
            skipped silently where it does not; or by kind of mechanism, as ``outputs``
            (``symkin.analysis.needs.DERIVED``).
        closure: the quantities to derive instead of ``outputs`` where the model's legs have no distance form
            (default: :data:`CLOSURE_OUTPUTS` where ``outputs`` is by kind, else ``outputs``).
        reading: the keyword arguments of :func:`symkin.model.load_model` a robot file is read with (tip, chain,
            snap_angles, ...: :func:`symkin.cli.urdf_args.urdf_options`); part of the derivation cache's key.
        display: the progress display shown while a model file derives (:data:`Display`).

    Raises:
        ModelError: a model file is invalid.
        GeneratedCodeError: a directory holds no usable generated code.
    """
    return load_models(path, (backend,), outputs, optional, closure, reading, display)[0]


def load_models(path: str, backends: Sequence[str],
                outputs: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = ANALYSIS_OUTPUTS,
                optional: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = (),
                closure: Sequence[str] | None = None, reading: Mapping[str, Any] | None = None,
                display: Display | None = None) -> list[Any]:
    """MODEL loaded once per backend (as :func:`generated_model`); a model file is derived once, for all of them.

    ``outputs`` may map the kind of mechanism ("serial", "parallel") to the quantities
    to derive (e.g. fk for a serial arm, the closed-form ik for a parallel one).
    """
    from symkin.viewer.notebook import load

    # The generated module is imported (numpy) or read (C, CasADi) by load(): the files may go afterwards.
    with generated_directory(path, backends, outputs, optional, closure, reading, display) as directory:
        return [load(directory, backend) for backend in backends]


def load_for_analysis(path: str, backend: str,
                      outputs: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = ANALYSIS_OUTPUTS,
                      optional: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = (),
                      display: Display | None = None) -> Any:
    """MODEL loaded with ``backend``'s code for an analysis (as :func:`generated_model`), except JAX's for legs the
    analyses continue (:attr:`symkin.mechanism.Sampling.CONTINUATION`): those get the :data:`HOST_BACKEND`'s code,
    and the loaded model's ``backend`` says so.  Such legs have no closed forms: the loop closure is solved point by
    point on the host (:mod:`symkin.mechanism.continuation`), where each call of the JAX code costs a dispatch (many
    times numpy's time for the same figures), and JAX has no device path for them.  The choice is read from the
    manifest before any code is loaded: a model file is derived once, its code emitted for both backends, and JAX's
    is loaded only where it is used (a generated directory without numpy's code keeps JAX's)."""
    from symkin.manifest import read_manifest
    from symkin.mechanism import Sampling, sampling_of
    from symkin.runtime.info import ModelInfo
    from symkin.viewer.notebook import load

    backends = (backend, HOST_BACKEND) if backend in DISPATCHED_BACKENDS else (backend,)
    with generated_directory(path, backends, outputs, optional, display=display) as directory:
        info = ModelInfo.from_manifest(read_manifest(directory))
        on_the_host = (backend in DISPATCHED_BACKENDS and HOST_BACKEND in info.backend_files
                       and sampling_of(info, info.functions) is Sampling.CONTINUATION)
        return load(directory, HOST_BACKEND if on_the_host else backend)


@contextlib.contextmanager
def generated_directory(path: str, backends: Sequence[str],
                        outputs: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = ANALYSIS_OUTPUTS,
                        optional: Sequence[str] | Mapping[MechanismKind, Sequence[str]] = (),
                        closure: Sequence[str] | None = None,
                        reading: Mapping[str, Any] | None = None, display: Display | None = None) -> Iterator[Path]:
    """The generated directory of MODEL while the block runs: MODEL itself, or for a model file
    a scratch directory it is derived into (``outputs``, ``optional``, ``closure``, ``reading`` and ``display`` as
    :func:`generated_model`)."""
    source = Path(path)
    if not is_model_file(path):
        yield source.parent if source.name == "manifest.json" else source
        return
    from symkin import pipeline_cache
    from symkin.atomic import replace_directory

    extra = optional if isinstance(optional, Mapping) else list(optional)
    request: dict[str, Any] = {"command": "analysis", "backends": list(backends), "outputs": outputs, "optional": extra}
    if closure is not None:
        request["closure"] = list(closure)
    if reading:
        request["reading"] = {name: reading[name] for name in sorted(reading)}
    key = pipeline_cache.request_key(source, request) if pipeline_cache.enabled() else None
    entry = None if key is None else pipeline_cache.lookup(key)
    with tempfile.TemporaryDirectory(prefix="symkin-analysis-") as scratch:
        if entry is not None:
            directory = Path(scratch) / entry.model
            replace_directory(directory, entry.files)
        else:
            directory = _derived(source, backends, outputs, optional, closure, scratch, key, reading or {},
                                 display or contextlib.nullcontext)
        yield directory


#: {(model name, model hash): (model, its derivation graph)} of the last model file derived in this process: a
#: command after another on the same mechanism (symkin identify after symkin excite, in a notebook or a test) reuses
#: the quantities derived before (the base parameters, the regressor) instead of deriving them again.  The model hash
#: covers everything the derivation reads (the mechanism, its parameters, bodies and drives; not the scene, which
#: only says what is emitted).  One entry: the graph of a large model holds many expressions.
_LAST_DERIVATION: dict[tuple[str, str], tuple[Model, Any]] = {}


def _derived(source: Path, backends: Sequence[str], outputs: Sequence[str] | Mapping[MechanismKind, Sequence[str]],
             optional: Sequence[str] | Mapping[MechanismKind, Sequence[str]], closure: Sequence[str] | None,
             scratch: str, key: str | None, reading: Mapping[str, Any], display: Display) -> Path:
    """The model file derived into ``scratch`` (and kept in the derivation cache under ``key``), its stages reported
    (:func:`symkin.reporting.report_progress`) to the ``display`` opened meanwhile."""
    from symkin import pipeline, pipeline_cache
    from symkin.derivation import Derivation
    from symkin.reporting import report_progress
    from symkin.model import load_model as load_model_file

    model = load_model_file(source, **reading)
    key_of_model = (model.name, model.hash)
    if key_of_model in _LAST_DERIVATION:    # the same mechanism as the last one derived here: its graph goes on
        model, derivation = _LAST_DERIVATION[key_of_model]
    else:
        derivation = Derivation(model)
        _LAST_DERIVATION.clear()
        _LAST_DERIVATION[key_of_model] = (model, derivation)
    wanted = outputs.get(analysis_kind(model), ANALYSIS_OUTPUTS) if isinstance(outputs, Mapping) else outputs
    if ((closure is not None or isinstance(outputs, Mapping)) and model.parallel is not None
            and not derivation.available(["distance_legs"])[0]):
        wanted = CLOSURE_OUTPUTS if closure is None else closure
    if isinstance(outputs, Mapping) and _limits_passive_joints(model):
        wanted = (*wanted, *PASSIVE_LIMIT_OUTPUTS)
    extra = optional.get(analysis_kind(model), ()) if isinstance(optional, Mapping) else optional
    names = dict.fromkeys([*wanted, *derivation.available(extra)[0]])  # in order, each once
    # no function 'combined' (the scene's fusion of every output): the analyses call the outputs one by one
    request = pipeline.resolve_request(model, ",".join(names), ",".join(backends), None, None, "none")
    with display(model.name):
        generation = pipeline.generate(model, request, report_progress, derivation=derivation)
    if key is not None:
        pipeline_cache.store(key, model.name, model.notes, generation.files)
    return pipeline.write(generation, scratch)


def analysis_kind(model: Model) -> MechanismKind:
    """The kind of a model file (:class:`symkin.mechanism.MechanismKind`, the keys of
    ``symkin.analysis.needs.NEEDS``)."""
    return MechanismKind.SERIAL if model.parallel is None else parallel_kind(model.task_space)


def _limits_passive_joints(model: Model) -> bool:
    """Whether a parallel model file declares limits on a passive joint variable."""
    return model.parallel is not None and any(
        joint.limits_of(k) is not None for leg in model.parallel.legs for joint in leg.joints
        for k in range(len(joint.variables)) if k != joint.active)

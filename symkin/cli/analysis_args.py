"""Arguments shared by the analysis commands (``symkin workspace``, ``symkin gci``, ``symkin bench gci``...):
MODEL (a generated directory or a model file, :mod:`symkin.analysis.model_files`), --set, --limit, outputs."""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NoReturn

from symkin.analysis.needs import NEEDS
from symkin.analysis.model_files import load_for_analysis, load_models
from symkin.cli.progress import Progress
from symkin.runtime.info import GeneratedModel

#: Length units of figures and design labels: metres per unit.
LENGTH_UNITS = {"m": 1.0, "cm": 100.0, "mm": 1000.0}


def add_model_arguments(p: argparse.ArgumentParser, *, backend: bool = True) -> None:
    """MODEL, --backend (unless ``backend`` is False), --set and --limit."""
    p.add_argument("model", metavar="MODEL",
                   help="generated model directory (from 'symkin derive', e.g. generated/planar_2r) "
                        "or a model file (YAML, or URDF; fk and jacobian are derived on the fly)")
    if backend:
        p.add_argument("--backend", default="numpy", metavar="NAME",
                       help="generated code to evaluate (default: %(default)s)")
    p.add_argument("--set", dest="assignments", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="parameter values instead of the defaults, e.g. --set l1=0.2,l2=0.2 (repeatable)")
    p.add_argument("--limit", dest="limits", action="append", default=[], metavar="JOINT=LOWER:UPPER",
                   help="joint limits instead of the model's, in rad or m; append 'deg' for degrees, "
                        "e.g. --limit theta2=-90deg:90deg (repeatable)")
    p.add_argument("--no-cache", action="store_true",
                   help="derive a model file afresh, not from the derivation cache (and keep nothing there)")


def design_label(model: GeneratedModel, values: dict[str, float], unit: str) -> str:
    """'l1 = 10 cm, l2 = 10 cm': a design's parameter values, lengths (unit m in the manifest) in ``unit``;
    'as declared' for the model's own values."""
    units = model.info.units
    parts = [f"{name} = {value * LENGTH_UNITS[unit]:g} {unit}" if units.get(name) == "m" else f"{name} = {value:g}"
             for name, value in values.items()]
    return ", ".join(parts) or "as declared"


def add_length_argument(p: argparse.ArgumentParser) -> None:
    """--length: the characteristic length of task spaces that mix translations and rotations."""
    p.add_argument("--length", metavar="L", default="auto",
                   help="characteristic length [m] for task spaces mixing translations and rotations, or "
                        "'auto' (default: the length minimizing the mean kappa_F^2)")


def parse_length(text: str) -> float | str:
    """A positive number of metres, or "auto".

    Raises:
        ValueError: anything else.
    """
    if text == "auto":
        return text
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"--length: '{text}' is neither a length in m nor 'auto'") from None
    if not value > 0:
        raise ValueError(f"--length must be positive, got {text}")
    return value


def resolve_length(model: GeneratedModel, text: str, limits: dict) -> float | None:
    """The characteristic length to use for ``model`` (None if its task space needs none).

    With "auto" the length is computed here, once, and printed.
    """
    from symkin import mechanism
    from symkin.mechanism import reach

    length = parse_length(text)
    if not mechanism.mixes_translations_and_rotations(model):
        return None
    if length != "auto":
        return float(length)
    computed = reach.characteristic_length_of(model, mechanism.joint_limits(model, limits))
    print(f"{model.name}: characteristic length L = {computed:.6g} m (minimizes the mean kappa_F^2; "
          "set with --length)")
    return computed


def parse_assignments(texts: list[str]) -> dict[str, float]:
    """``["l1=0.2,l2=0.2", "m1=1"]`` -> {"l1": 0.2, "l2": 0.2, "m1": 1.0}.

    Raises:
        ValueError: an entry is not NAME=NUMBER.
    """
    values: dict[str, float] = {}
    for text in texts:
        for item in filter(None, (part.strip() for part in text.split(","))):
            name, sep, value = item.partition("=")
            if not sep or not name.strip():
                raise ValueError(f"'{item}' is not NAME=VALUE")
            try:
                values[name.strip()] = float(value)
            except ValueError:
                raise ValueError(f"'{item}': '{value}' is not a number") from None
    return values


def parse_value(text: str) -> float:
    """A number of rad or m, or of degrees with a 'deg' suffix (converted to rad).

    Raises:
        ValueError: not a number.
    """
    text = text.strip()
    if text.endswith("deg"):
        return math.radians(float(text[:-3]))
    return float(text)


def parse_ranges(texts: list[str], option: str, name: str = "NAME") -> dict[str, tuple[float, float]]:
    """``["a=0.05:0.2,theta2=-90deg:90deg"]`` -> {"a": (0.05, 0.2), "theta2": (-pi/2, pi/2)}.

    Each text holds comma-separated NAME=LOWER:UPPER entries (numbers as :func:`parse_value`
    reads them, so 'deg' works); a later entry of a name replaces an earlier one.

    Raises:
        ValueError: an entry is not NAME=LOWER:UPPER with numbers and LOWER < UPPER (the
            message names ``option`` and the entry).
    """
    ranges: dict[str, tuple[float, float]] = {}
    for text in texts:
        for item in filter(None, (part.strip() for part in text.split(","))):
            key, sep, span = item.partition("=")
            lower, colon, upper = span.partition(":")
            if not sep or not colon or not key.strip():
                raise ValueError(f"{option} '{item}' is not {name}=LOWER:UPPER")
            try:
                bounds = (parse_value(lower), parse_value(upper))
            except ValueError:
                raise ValueError(f"{option} '{item}': LOWER and UPPER must be numbers (optionally with 'deg')") from None
            if not bounds[0] < bounds[1]:
                raise ValueError(f"{option} '{item}': LOWER must be smaller than UPPER")
            ranges[key.strip()] = bounds
    return ranges


def parse_limits(texts: list[str]) -> dict[str, tuple[float, float]]:
    """The joint limits of ``--limit JOINT=LOWER:UPPER`` options (see :func:`parse_ranges`)."""
    return parse_ranges(texts, "--limit", "JOINT")


def model_from_args(args: argparse.Namespace) -> tuple[Any, dict[str, tuple[float, float]]]:
    """The model of MODEL with --set applied, and the --limit overrides; with --backend jax, legs without closed forms
    get the numpy code, and the first line printed says so (:func:`say_where_continued`).

    Raises:
        ValueError: malformed --set or --limit (KeyError for an unknown parameter).
    """
    model = load_for_analysis(args.model, args.backend, NEEDS["kinematics"],
                              DEVICE_OUTPUTS if getattr(args, "device", False) else (), display=Progress)
    say_where_continued(args.backend, model)
    return with_assignments(args, [model])[0], parse_limits(args.limits)


def say_where_continued(backend: str, model: Any) -> None:
    """Say (stdout) how ``model``, asked for with ``backend``, continues legs without closed forms: the loop closure
    is solved point by point on the host (:func:`symkin.analysis.model_files.load_for_analysis`), so with the numpy
    code that was loaded instead; or, where a generated directory holds JAX's code alone, with it, one dispatch per
    call (many times numpy's time for the same figures), and how to get the numpy code."""
    from symkin import mechanism
    from symkin.analysis.model_files import DISPATCHED_BACKENDS, HOST_BACKEND

    if model.backend != backend:
        print(f"{model.name}: --backend {backend}: its legs have no closed forms, so the loop closure is continued "
              f"point by point on the host, with the {model.backend} code (JAX has no device path for them yet)",
              flush=True)
    elif backend in DISPATCHED_BACKENDS and mechanism.sampling(model) is mechanism.Sampling.CONTINUATION:
        print(f"{model.name}: --backend {backend}: its legs have no closed forms and {model.directory} holds no "
              f"{HOST_BACKEND} code, so the loop closure is continued point by point with the {backend} code, one "
              f"dispatch per call (many times {HOST_BACKEND}'s time for the same figures): derive it with --backend "
              f"{HOST_BACKEND} too", flush=True)


def models_from_args(args: argparse.Namespace,
                     backends: Sequence[str]) -> tuple[list[Any], dict[str, tuple[float, float]]]:
    """MODEL loaded once per backend (a model file derived once), with --set applied, and the
    --limit overrides (see :func:`model_from_args`)."""
    models = load_models(args.model, backends, NEEDS["kinematics"],
                         DEVICE_OUTPUTS if getattr(args, "device", False) else (), display=Progress)
    return with_assignments(args, models), parse_limits(args.limits)


def with_assignments(args: argparse.Namespace, models: list[Any]) -> list[Any]:
    """``models`` with the --set values bound (KeyError for an unknown parameter)."""
    values = parse_assignments(args.assignments)
    return [model.bind(**values) for model in models] if values else models


def per_joint(option: str, text: str, count: int) -> list[float]:
    """``T[,T...]``: one number for every joint, or one per joint (``option`` names it in the message).

    Raises:
        ValueError: not numbers separated by commas, or neither 1 nor ``count`` of them.
    """
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"{option} '{text}': write numbers separated by commas") from None
    if len(values) not in (1, count):
        raise ValueError(f"{option}: give one value or {count} (one per actuator), got {len(values)}")
    return values * count if len(values) == 1 else values


def effort_limits(text: str | None, model: GeneratedModel) -> list[float] | None:
    """--effort-limit ``text``, else the model's effort limits; None where it declares none for some actuator."""
    count = len(model.info.coordinates)
    if text:
        return per_joint("--effort-limit", text, count)
    declared = [c.effort_limit for c in model.info.coordinates]
    return [float(v) for v in declared if v is not None] if None not in declared else None


def fail_on_bad_input(args: argparse.Namespace, err: Exception) -> NoReturn:
    """Report a bad argument or an analysis that does not apply to the model; exit code 2.  The message alone,
    with a pointer to --help: the whole usage text before it hid the one line that says what is wrong."""
    message = err.args[0] if isinstance(err, KeyError) and err.args else str(err)
    parser: argparse.ArgumentParser = args.parser
    parser.exit(2, f"{parser.prog}: error: {message}\n  (see '{parser.prog} --help')\n")


#: The image formats matplotlib writes without extra packages, by file suffix.
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".eps", ".ps", ".jpg", ".jpeg", ".tif", ".tiff", ".webp")


def figure_path(text: str) -> str:
    """A figure's file name, its format told by its suffix (an argparse type: refused before any work)."""
    if not text.lower().endswith(FIGURE_SUFFIXES):
        raise argparse.ArgumentTypeError(f"'{text}' names no image format: end it in one of "
                                         f"{', '.join(FIGURE_SUFFIXES)} (e.g. '{text}.png')")
    return text


def sample_count(text: str) -> int:
    """A sample count, also written like 1e9 (an argparse type)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number of samples") from None
    if not (value >= 1 and value == int(value)):
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole positive number of samples")
    return int(value)


def add_chunk_arguments(p: argparse.ArgumentParser, what: str) -> None:
    """--scheduler, --workers, --chunk: ``what`` in chunks of points as Dask tasks (symkin.runtime.cluster)."""
    p.add_argument("--scheduler", metavar="local|serial|tcp://HOST:PORT", default=None,
                   help=f"{what} in chunks of --chunk points, as Dask tasks: on a LocalCluster (local), in this "
                        "process (serial) or on the scheduler at an address; memory is bounded by the chunk, so -n "
                        "may be 1e9 or more (default: all points at once, in this process)")
    p.add_argument("--workers", type=int, default=None, metavar="K",
                   help="LocalCluster: worker processes (default: one per core)")
    p.add_argument("--chunk", type=int, default=2**20, metavar="N", help="points per task (default: %(default)s)")


#: What a hybrid device's whole-device analyses (--device) derive from a model file besides the platform's.
DEVICE_OUTPUTS = ("device_fk", "device_actuator_jacobian")


def add_device_argument(p: argparse.ArgumentParser) -> None:
    """--device: analyse a hybrid device as a whole (symkin.mechanism.device.WholeDevice)."""
    p.add_argument("--device", action="store_true",
                   help="a parallel platform carrying a wrist (a hybrid device): analyse the whole device in its "
                        "actuated joints (legs, then wrist), the wrist's TCP and its actuator Jacobian, with a "
                        "characteristic length (default: the platform alone)")


def device_view(args: argparse.Namespace, model: Any) -> Any:
    """The model, or with --device the whole device (:class:`symkin.mechanism.device.WholeDevice`)."""
    if not getattr(args, "device", False):
        return model
    from symkin.mechanism.device import WholeDevice

    return WholeDevice(model)


def add_orientation_argument(p: argparse.ArgumentParser) -> None:
    """--orientation: the constant orientation at which a rotating platform is analysed (workspace, gci)."""
    p.add_argument("--orientation", metavar="ROLL,PITCH,YAW",
                   help="platforms that also rotate (Stewart-Gough): the constant orientation of the analysed "
                        "workspace, R = Rz(yaw) Ry(pitch) Rx(roll), in rad, or in degrees with 'deg' "
                        "(e.g. 0,10deg,0); default: the orientation of the model's home pose (parallel.home)")


def parse_orientation(text: str | None) -> list[float] | None:
    """--orientation ROLL,PITCH,YAW as angles in rad (None if not given).

    Raises:
        ValueError: not three numbers.
    """
    if text is None:
        return None
    parts = text.split(",")
    try:
        if len(parts) != 3:
            raise ValueError
        return [parse_value(part) for part in parts]
    except ValueError:
        raise ValueError(f"--orientation: '{text}' is not ROLL,PITCH,YAW (three numbers in rad, or with 'deg', "
                         "e.g. 0,10deg,0)") from None


def write_outputs(out: Path, files: Mapping[str, str | bytes], start: float) -> None:
    """Replace the directory ``out`` with ``files`` as a whole (atomically), then print their ``summary.txt`` and
    what was written, with the time since ``start`` (``symkin rate``, ``identify``, ``excite``)."""
    from symkin.atomic import replace_directory

    replace_directory(out, dict(files))
    print(str(files["summary.txt"]), end="")
    print(f"wrote {len(files)} files to {out}/ ({', '.join(sorted(files))}) in {time.perf_counter() - start:.2f} s")

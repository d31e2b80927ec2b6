"""``symkin view``: one self-contained HTML page that shows a mechanism in 3D.

The page (``templates/viewer/page.html.j2``) carries everything it needs, so it opens with no
network: the model's generated JavaScript (:mod:`symkin.backends.js`) computes the pose at every
slider move (serial: ``frames``, ``fk`` and ``jacobian`` of q; parallel: the closed-form ``ik``,
``leg_points`` and the Jacobian of p; legs of any topology: Gauss-Newton on the ``closure`` and its
``closure_jacobians`` from the last assembly, drawn by ``leg_joints``; a hybrid device's wrist:
``device_frames`` and ``device_fk`` of p and its joints qw), three.js (vendored in ``symkin/viewer/vendor`` with its
MIT licence, embedded as data: modules behind an import map) draws it, and the workspace cloud
with 1/kappa per point (seed Table 8.5) is computed here by the analyses, for the design given.

Length: the page's data (sliders, cloud, home pose) for every kind of mechanism the analyses know, each a
few lines, with the one rendering and safety path (escaping, CSP hashes) they all share.

The conditioning the page shows is that of the analyses (:func:`symkin.analysis.global_indices.local_index`):
the same task Jacobian, homogenized by the same characteristic length when the task space mixes
lengths and angles, and for a pose platform the twist Jacobian of
:class:`symkin.mechanism.reach.ConstantOrientation`.
"""

from __future__ import annotations

import base64
import hashlib
import math
from dataclasses import dataclass
from importlib import resources
from collections.abc import Callable
from typing import Any

import numpy as np
from jinja2.utils import htmlsafe_json_dumps
from markupsafe import Markup

from symkin.mechanism.closure import CLOSED, MAX_STEP, SOLVE_ITERATIONS, SOLVE_TOLERANCE, assemble_at_home
from symkin._version import __version__
from symkin.numerics import conditioning, sampling
from symkin.analysis import continued_workspace, global_indices, workspace
from symkin.mechanism import reach
from symkin.analysis.needs import NEEDS
from symkin import mechanism
from symkin.mechanism import Limits, MechanismKind
from symkin.backends.templating import render_html
from symkin.runtime.info import GeneratedModel
from symkin.runtime.loader import LoadedModel

TEMPLATE = "viewer/page.html.j2"
#: three.js release of the vendored files (symkin/viewer/vendor/VENDOR.md).
THREE_VERSION = "170"
#: Below this 1/kappa the page warns of a singular configuration.
SINGULAR_THRESHOLD = 0.01
#: Decimal places of the cloud's coordinates (m) and indices in the page: 1 um, far below a pixel.
CLOUD_DIGITS = 6
#: Largest Sobol sample (log2) of a pose platform's box when looking for its reachable points.
MAX_SOBOL_LOG2 = 18
#: The first grid of legs solved through their closure has at least this many cells a side (a coarser one steps
#: farther than Gauss-Newton follows from a neighbour, as symkin rate's grid) ...
MIN_CLOSURE_CELLS = 8
#: ... and is refined to at most this many times the first grid's cells a side.
REFINED_CELLS_LIMIT = 4
#: Viridis at 5 stops (matplotlib's table): the cloud's colours and the colour bar.
VIRIDIS = ("#440154", "#3b528b", "#21918c", "#5ec962", "#fde725")


@dataclass(frozen=True)
class Cloud:
    """Workspace points (N, 3) in m with the analyses' 1/kappa (N,), the joints q (N, n) and the
    characteristic length used to homogenize J (None when the task space has one unit); for legs solved through
    their closure, the passive joints' variables s (N, ns), the task poses p (N, m) and the home assembly (q, s)
    the page starts from too."""

    points: np.ndarray
    inverse_kappa: np.ndarray
    q: np.ndarray
    length: float | None
    note: str
    s: np.ndarray | None = None
    poses: np.ndarray | None = None
    home_assembly: tuple[np.ndarray, np.ndarray] | None = None


class ViewUnavailable(ValueError):
    """A model directory without what the page evaluates (the message says how to derive it)."""


#: ... and a hybrid device's wrist on the platform: its links' frames, the TCP and the wrist's angular Jacobian.
WRIST_VIEW_OUTPUTS = ("device_fk", "device_frames", "device_jacobian")
#: Legs without closed forms (:func:`symkin.mechanism.closure.uses_closure`): the page solves the closure
#: for (q, s) from the last assembly, J = dp/dq from its Jacobians, and draws every joint of every leg.
CLOSURE_VIEW_OUTPUTS = ("closure", "closure_jacobians", "leg_joints")
#: What a model file is also derived with for the page where the model has it: a wrist's functions, every leg joint.
OPTIONAL_VIEW_OUTPUTS = (*WRIST_VIEW_OUTPUTS, "leg_joints")


def view_outputs(model: GeneratedModel) -> tuple[str, ...]:
    """The generated functions the page evaluates for ``model``."""
    if _solved_through_closure(model):
        return CLOSURE_VIEW_OUTPUTS
    return NEEDS["view"][mechanism.kind_of(model)] + (WRIST_VIEW_OUTPUTS if model.info.wrist else ())


def _solved_through_closure(model: GeneratedModel) -> bool:
    """A parallel model without the closed-form ik whose directory holds the closure's functions (legs of any
    topology; a directory derived with only some of them is told which it lacks)."""
    return (mechanism.is_parallel(model) and "ik" not in model.functions
            and any(name in model.functions for name in CLOSURE_VIEW_OUTPUTS))


def missing_functions(model: GeneratedModel) -> list[str]:
    """The generated functions the page needs that ``model`` lacks (empty: it can be shown)."""
    return [f for f in view_outputs(model) if f not in model.functions]


def _pad3(points: np.ndarray, axes: tuple[str, ...]) -> np.ndarray:
    out = np.zeros((len(points), 3))
    for k, axis in enumerate(axes):
        out[:, "xyz".index(axis)] = points[:, k]
    return out


def _length(model: GeneratedModel, limits: np.ndarray) -> float | None:
    """The characteristic length that homogenizes J where the rated task space mixes lengths and angles
    (a pose platform's twist, at its home orientation), as the analyses compute it; else None."""
    if mechanism.kind_of(model) is MechanismKind.PARALLEL_POSE:
        return reach.characteristic_length_of(reach.constant_orientation(model), limits)
    return reach.characteristic_length_of(model, limits) if mechanism.mixes_translations_and_rotations(model) \
        else None


def workspace_cloud(model: GeneratedModel, samples: int, seed: int = 0, limits: Limits | None = None) -> Cloud:
    """The workspace cloud with 1/kappa, as ``symkin workspace`` and ``symkin gci`` sample it (``limits``: the
    actuators' limit overrides, :func:`symkin.mechanism.joint_limits`)."""
    if _solved_through_closure(model):
        return _closure_cloud(model, samples, limits)
    if mechanism.kind_of(model) is MechanismKind.PARALLEL_ORIENTATION:
        n = len(model.info.coordinates)
        return Cloud(np.zeros((0, 3)), np.zeros(0), np.zeros((0, n)), None,
                     "no workspace cloud: a spherical platform's workspace is a set of orientations, not of points.")
    bounds = mechanism.joint_limits(model, limits)
    length = _length(model, bounds)
    homogenized = f"; J homogenized with L = {1000 * length:.1f} mm." if length is not None else "."
    if mechanism.kind_of(model) is MechanismKind.PARALLEL_POSE:
        held = reach.constant_orientation(model)
        lower, upper = reach.constant_orientation_box(held, bounds)
        log2 = max(1, math.ceil(math.log2(samples)))
        while True:  # about ``samples`` reachable points: the box holds the workspace loosely
            points = sampling.sobol(lower, upper, log2, np.random.default_rng(seed))
            q, reachable = reach.reachable_points(held, points, bounds)
            found = max(int(reachable.sum()), 1)
            if found >= samples / 2 or log2 >= MAX_SOBOL_LOG2:
                break
            log2 = min(MAX_SOBOL_LOG2, log2 + math.ceil(math.log2(samples / found)))
        index = global_indices.scaled_index(held, conditioning.inverse_condition_number, length, bounds)
        values = index(held.jacobian(q[reachable], points[reachable]))
        note = (f"{int(reachable.sum())} reachable platform centres of {len(points)} Sobol points, platform held at "
                f"roll, pitch, yaw = {reach.orientation_text(held)}{homogenized}")
        return Cloud(points[reachable], values, q[reachable], length, note)
    cloud = workspace.sample_workspace(model, samples, limits=limits, seed=seed)
    if 0 < len(cloud.q) < samples / 2:  # the joint stops keep part of the limits' box (the PHANToM's a quarter)
        cloud = workspace.sample_workspace(model, math.ceil(samples ** 2 / len(cloud.q)), limits=limits, seed=seed)
    values = global_indices.local_index(model, cloud.q, length=length)
    note = f"{len(cloud.q)} joint configurations sampled within the limits{homogenized}"
    return Cloud(_pad3(cloud.points, cloud.axes), values, cloud.q, length, note)


def _closure_cloud(model: GeneratedModel, samples: int, limits: Limits | None) -> Cloud:
    """The cell centres of the working mode of the home assembly on a grid of about ``samples`` cells, at the home
    orientation, with 1/kappa (:func:`symkin.analysis.continued_workspace.continued_workspace`)."""
    task = mechanism.task_space(model)
    axes = tuple(c for c in task if c in mechanism.POSITION_COMPONENTS)
    start = assemble_at_home(model)
    if not axes:
        return Cloud(np.zeros((0, 3)), np.zeros(0), np.zeros((0, len(model.info.coordinates))), None,
                     "no workspace cloud: the platform's workspace is a set of orientations, not of points.",
                     home_assembly=start)
    cells = max(MIN_CLOSURE_CELLS, round(samples ** (1 / len(axes))))
    found = continued_workspace.continued_workspace(model, limits=limits, cells=cells, start=start)
    count = int(found.occupancy.occupied.sum())
    if count < samples / 2:  # the grid's box holds the workspace loosely: refine to about ``samples`` cells
        cells = min(round(cells * (samples / max(count, 1)) ** (1 / len(axes))), REFINED_CELLS_LIMIT * cells)
        found = continued_workspace.continued_workspace(model, limits=limits, cells=cells, start=start, box=found.box)
    reached = found.occupancy.occupied
    poses = np.repeat(found.pose[None], int(reached.sum()), axis=0)
    poses[:, list(mechanism.position_rows(model))] = found.occupancy.centers()[reached]
    angles = ", ".join(f"{name} = {found.pose[k]:.4g} rad" for k, name in enumerate(task) if name not in axes)
    orientation = f", platform held at {angles}" if angles else ""
    homogenized = f"; J homogenized with L = {1000 * found.length:.1f} mm" if found.length is not None else ""
    note = (f"{int(reached.sum())} cells of {1000 * float(found.occupancy.cell.max()):.3g} mm reached by continuing "
            f"the loop closure from the home pose (the home assembly's working mode){orientation}{homogenized}.")
    return Cloud(_pad3(found.occupancy.centers()[reached], axes), found.inv_kappa[reached], found.q[reached],
                 found.length, note, found.s[reached], poses, start)


def no_cloud(model: GeneratedModel, limits: Limits | None = None) -> Cloud:
    """An empty cloud (``--workspace 0``); a mixed task space still gets its characteristic length (but for legs
    solved through their closure, whose length is computed over the cells of the cloud: the page then rates J
    unhomogenized, and says so)."""
    n = len(model.info.coordinates)
    if _solved_through_closure(model):
        return Cloud(np.zeros((0, 3)), np.zeros(0), np.zeros((0, n)), None,
                     "no workspace cloud (--workspace 0); 1/kappa of J unhomogenized (no characteristic length).",
                     home_assembly=assemble_at_home(model))
    return Cloud(np.zeros((0, 3)), np.zeros(0), np.zeros((0, n)), _length(model, mechanism.joint_limits(model, limits)),
                 "no workspace cloud (--workspace 0).")


def _slider_units(unit: str, revolute: bool | None = None) -> tuple[float, str, float]:
    """(scale to SI, shown unit, step) of a slider: angles in degrees, lengths in mm."""
    if revolute or unit == "rad":
        return math.pi / 180, "deg", 0.1
    if unit == "m" or revolute is False:
        return 1e-3, "mm", 0.1
    return 1.0, unit, 0.001


def _on_grid(value: float, scale: float, step: float, direction: int = 0) -> float:
    """``value`` (SI) on the slider's grid, a multiple of ``step`` in the shown unit: the nearest
    (``direction`` 0), the next below (-1) or above (+1).  A range input snaps to min + k step, so bounds
    and start values on that grid keep the values the arrow keys give exact."""
    k = value / scale / step
    if abs(k - round(k)) < 1e-6 or direction == 0:
        return round(k) * step * scale
    return (math.floor(k) if direction < 0 else math.ceil(k)) * step * scale


def _slider(name: str, lower: float, upper: float, scale: float, unit: str, step: float) -> dict[str, Any]:
    """A slider's spec: bounds moved inwards onto its grid (so a joint slider stays within the limits)."""
    return {"name": name, "lower": _on_grid(lower, scale, step, +1), "upper": _on_grid(upper, scale, step, -1),
            "scale": scale, "unit": unit, "step": step}


def _coordinates(model: GeneratedModel, limits: Limits | None) -> list[dict[str, Any]]:
    return [_slider(c.name, float(lower), float(upper), *_slider_units("", c.revolute))
            | {"label": c.label, "revolute": bool(c.revolute)}
            for c, (lower, upper) in zip(model.info.coordinates, mechanism.joint_limits(model, limits))]


def _wrist(model: GeneratedModel) -> list[dict[str, Any]]:
    """Sliders of a hybrid device's wrist joints, over their declared limits (a full turn, or +-0.1 m, without)."""
    out = []
    for c in model.info.wrist:
        unlimited = mechanism.DEFAULT_REVOLUTE_LIMITS if c.revolute else (-0.1, 0.1)
        lower, upper = c.limits if c.limits is not None else unlimited
        out.append(_slider(c.name, float(lower), float(upper), *_slider_units("", c.revolute)) | {"label": c.label})
    return out


def _parameters(model: GeneratedModel, outputs: tuple[str, ...]) -> list[dict[str, Any]]:
    used = {p for f in outputs if f in model.info.functions for p in model.info.functions[f].parameters}
    out = []
    for p in model.info.parameters:
        if p.fixed or p.name not in used:
            continue
        value = float(model.parameters[p.name])
        scale, unit, step = _slider_units(p.unit)
        spread = 0.5 * abs(value) if value else 0.1
        out.append(_slider(p.name, value - spread, value + spread, scale, unit, step) | {"value": value})
    return out


def _task(model: GeneratedModel, cloud: Cloud, home: np.ndarray) -> list[dict[str, Any]]:
    """Sliders of the task coordinates: positions over the cloud's box (10 % margin), angles +-30 deg about home."""
    names = mechanism.task_space(model)
    if len(cloud.points):
        lower, upper = cloud.points.min(axis=0), cloud.points.max(axis=0)
    else:
        lower, upper = home[:3] - 0.05, home[:3] + 0.05
    margin = 0.1 * (upper - lower)
    out = []
    for k, name in enumerate(names):
        if name in mechanism.POSITION_COMPONENTS:
            scale, unit, step = _slider_units("m")
            bounds = (float(lower[k] - margin[k]), float(upper[k] + margin[k]))
        else:
            scale, unit, step = _slider_units("rad")
            bounds = (float(home[k]) - math.pi / 6, float(home[k]) + math.pi / 6)
        out.append(_slider(name, *bounds, scale, unit, step))
    return out


def page_data(model: GeneratedModel, cloud: Cloud, limits: Limits | None = None) -> dict[str, Any]:
    """Everything the page's program reads (the JSON in ``<script id="symkin-data">``); ``limits``: the actuators'
    limit overrides."""
    kind = "parallel" if mechanism.is_parallel(model) else "serial"
    outputs = view_outputs(model)
    points = np.round(cloud.points, CLOUD_DIGITS)
    values = np.round(np.nan_to_num(cloud.inverse_kappa, nan=0.0), CLOUD_DIGITS)
    coordinates = _coordinates(model, limits)
    if kind == "serial":
        # start at the best-conditioned sampled configuration (else 0 within the limits)
        q = cloud.q[int(np.argmax(values))] if len(values) else np.clip(0.0, *mechanism.joint_limits(model, limits).T)
        home: dict[str, list[float]] = {"q": [_on_grid(v, c["scale"], c["step"]) for v, c in zip(q, coordinates)]}
    else:
        units = [_slider_units("m" if c in mechanism.POSITION_COMPONENTS else "rad") for c in mechanism.task_space(model)]
        home = {"q": [0.0] * len(model.info.coordinates),
                "p": [_on_grid(v, scale, step) for v, (scale, _, step) in zip(mechanism.home_pose(model), units)]}
        if cloud.home_assembly is not None:  # legs solved through their closure: the page continues it
            q0, s0 = cloud.home_assembly
            home |= {"q": q0.tolist(), "s": s0.tolist()}
        wrist = _wrist(model)
        if wrist:  # a hybrid device: its wrist starts in the middle of its sliders
            home["qw"] = [_on_grid((w["lower"] + w["upper"]) / 2, w["scale"], w["step"]) for w in wrist]
    seen = np.concatenate([points, _mechanism_points(model, home)])
    lower, upper = seen.min(axis=0), seen.max(axis=0)
    centre, scale = (lower + upper) / 2, float(np.max(upper - lower))
    data: dict[str, Any] = {
        "name": model.name, "kind": kind, "coordinates": coordinates, "home": home,
        "task_space": list(mechanism.task_space(model)),
        "parameters": _parameters(model, outputs),
        "conditioning": {"twist": "inverse_jacobian" in outputs, "length": cloud.length,
                         "position_rows": list(mechanism.position_rows(model))},
        "singular_threshold": SINGULAR_THRESHOLD,
        "cloud": {"points": points.tolist(), "inverse_kappa": values.tolist(),
                  "colour_max": float(max(values.max(initial=0.0), 1e-12)),
                  # what the page recomputes the cloud from for another design: the joint samples, a pose
                  # platform's sampled centres (rounded as the points are), or each cell's (q, s) to solve from
                  "samples": _cloud_samples(cloud, points, outputs)},
        "scale": scale if scale > 0 else 1.0, "view_target": centre.tolist(),
    }
    if model.info.tree is not None:  # a branched serial model: the page draws each link from its parent
        data["tree"] = model.info.tree
    if kind == "parallel":
        data["task"] = _task(model, cloud, np.array(home["p"]))
    if cloud.home_assembly is not None:  # the page's Gauss-Newton takes the analyses' settings
        data["closure"] = {"max_step": MAX_STEP, "tolerance": SOLVE_TOLERANCE,
                           "closed": CLOSED, "iterations": SOLVE_ITERATIONS}
    if "qw" in home:
        data["wrist"] = wrist
    return data


def _cloud_samples(cloud: Cloud, points: np.ndarray, outputs: tuple[str, ...]) -> list:
    if cloud.s is not None and cloud.poses is not None:  # legs solved through their closure: each cell's pose and
        return [{"p": p, "q": q, "s": s}                  # the (q, s) its solve starts from
                for p, q, s in zip(cloud.poses.tolist(), cloud.q.tolist(), cloud.s.tolist())]
    return (points if "inverse_jacobian" in outputs else np.round(cloud.q, CLOUD_DIGITS + 3)).tolist()


def _mechanism_points(model: GeneratedModel, home: dict[str, list[float]]) -> np.ndarray:
    """The joints' positions (k, 3) at the first pose shown: with the cloud, what the camera frames."""
    if "p" not in home:
        frames = model.frames(np.array(home["q"]))
        return np.array([[0.0, 0.0, 0.0]] + [T[:3, 3] for T in frames])
    if "s" in home:
        return np.concatenate(tuple(model.leg_joints(np.array(home["q"]), np.array(home["s"]))))
    p = np.array(home["p"])
    legs = np.asarray(model.leg_points(model.ik(p).joints, p))
    if "qw" not in home:
        return legs
    return np.concatenate([legs, model.device_fk(p, np.array(home["qw"]))[None, :3, 3]])


def _vendor(name: str) -> str:
    return resources.files("symkin.viewer").joinpath("vendor", name).read_text(encoding="utf-8")


def _module_url(source: str) -> str:
    return "data:text/javascript;base64," + base64.b64encode(source.encode("utf-8")).decode("ascii")


def _inline_script(text: str, what: str) -> Markup:
    """``text`` as the content of an inline ``<script>``, once checked to hold nothing that ends the element
    (``</script``) or moves the HTML parser into its escaped script states (``<!--``)."""
    lowered = text.lower()
    for marker in ("</script", "<!--"):
        if marker in lowered:
            raise ValueError(f"{what} contains '{marker}' and cannot be inlined in the page (symkin derive "
                             "writes its comments without it: derive the model again)")
    return Markup(text)  # checked above; a script is code, not text to escape


def _json_island(value: Any) -> Markup:
    """``value`` as JSON for an inline ``<script type="application/json">`` or import map: ``<``, ``>``,
    ``&``, ``'`` and every non-ASCII character (U+2028/9 too) as \\u escapes, so no text in it can end the
    element, open a comment or break a line."""
    return htmlsafe_json_dumps(value, separators=(",", ":"), allow_nan=False)


def _script_hash(text: str) -> str:
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii") + "'"


def content_security_policy(scripts: list[str]) -> str:
    """The page's Content-Security-Policy: nothing from the network; scripts only the page's own inline ones
    (by their SHA-256, so an injected inline script or event handler would not run) and its data: modules."""
    return "; ".join([
        "default-src 'none'",
        "script-src " + " ".join([_script_hash(s) for s in scripts] + ["data:"]),
        "style-src 'unsafe-inline'",
        "img-src data: blob:",
        "base-uri 'none'",
        "form-action 'none'",
    ])


def render_page(model: GeneratedModel, model_script: str, cloud: Cloud, description: str,
                limits: Limits | None = None) -> str:
    """The page's HTML text: ``model`` (a loaded model, bound to the design to show), the text of its
    generated JavaScript module, its workspace ``cloud`` (:func:`workspace_cloud`).

    Every text from the model (names, description, notes) is HTML-escaped by the page's jinja environment;
    data goes in as a JSON island (:func:`_json_island`); the scripts are checked (:func:`_inline_script`)
    and pinned by hash in the Content-Security-Policy.
    """
    data = page_data(model, cloud, limits)
    top = data["cloud"]["colour_max"]
    importmap = _json_island({"imports": {
        "three": _module_url(_vendor("three.module.min.js")),
        "three/addons/controls/OrbitControls.js": _module_url(_vendor("OrbitControls.js"))}})
    scripts = [_inline_script(model_script, f"the JavaScript module of {model.name}"),
               _inline_script(resources.files("symkin.templates").joinpath("viewer", "viewer.js")
                              .read_text(encoding="utf-8"), "viewer.js")]
    return render_html(
        TEMPLATE,
        csp=content_security_policy([str(importmap)] + [str(s) for s in scripts]),
        provenance=f"Generated by symkin {__version__} (symkin view) from model '{model.name}'",
        title=f"{model.name}: symkin view", description=description, sliders_heading=_sliders_heading(data),
        wrist="wrist" in data,
        version=__version__,
        three_version=THREE_VERSION, cloud_note=cloud.note,
        gradient=", ".join(VIRIDIS), ticks=[f"{t:.2f}" for t in (0.0, top / 2, top)],
        data=_json_island(data), importmap=importmap, model_script=scripts[0], viewer_script=scripts[1],
        three_licence=_vendor("LICENSE-three.txt").replace("--", "- -"),
    )


def model_script(model: LoadedModel) -> str:
    """The text of the model's generated JavaScript, once checked to hold the functions the page evaluates.

    Raises:
        ViewUnavailable: the directory lacks them; the message names what and how to derive it.
    """
    missing = missing_functions(model)
    script = model.directory / f"{model.name}.js"
    if missing or not script.is_file():
        what = ", ".join(missing) if missing else "its JavaScript"
        raise ViewUnavailable(f"{model.directory}: the page needs {what}; derive the model with them, e.g. symkin "
                              f"derive MODEL --only {','.join(view_outputs(model))} --backend numpy,js")
    text = script.read_text(encoding="utf-8")
    try:
        _inline_script(text, str(script))
    except ValueError as err:
        raise ViewUnavailable(str(err)) from None
    return text


def _sliders_heading(data: dict[str, Any]) -> str:
    """What the sliders move and how the page solves for the rest: the joints of a serial model, the platform of a
    parallel one through its closed-form ik, or through Gauss-Newton on the loop closure (legs of any topology)."""
    if data["kind"] == "serial":
        return "Joints"
    if "s" in data["home"]:
        return "Platform (legs solved by Gauss-Newton on the loop closure, from the home assembly)"
    return "Platform (closed-form inverse kinematics)"


def page_of(model: LoadedModel, samples: int, seed: int = 0,
            progress: Callable[[str], None] = lambda _stage: None, limits: Limits | None = None) -> tuple[str, Cloud]:
    """(the page's HTML, its workspace cloud) for a loaded model (bound to the design to show) with about
    ``samples`` cloud points (0: none), the actuators' limits overridden by ``limits`` ({joint: (lower, upper)}).

    Raises:
        ViewUnavailable: see :func:`model_script`.
        ValueError: the workspace cannot be sampled (e.g. no reachable point).
    """
    script = model_script(model)
    progress(f"sampling the workspace ({samples} points)")
    cloud = workspace_cloud(model, samples, seed, limits) if samples else no_cloud(model, limits)
    progress("writing the page")
    description = model.info.description or model.name
    return render_page(model, script, cloud, description, limits), cloud

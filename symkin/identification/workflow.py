"""The identification of a device from a run, as ``symkin identify`` does it (issue 33; issue 62: the workflow
below the command line).

:func:`identify` loads the model (a generated directory, or a model file derived on the fly with what
``DERIVED["identify"]`` lists), binds its regressors to what the run records (the device's actuated joints,
:func:`symkin.identification.device_regressors.run_regressors`), reads the run, estimates the base parameters
(least squares, weighted least squares, the energy balance, or physically consistent standard parameters), validates
them on the held-out end of the run and, given a model file, rewrites it with the identified values
(:mod:`symkin.identification.identified_model`).  It returns the files of the output directory; the command writes
them (atomically).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symkin.analysis import model_files
from symkin.analysis.needs import DERIVED


@dataclass(frozen=True)
class IdentifyRequest:
    """What to identify and how (the options of ``symkin identify``).

    Attributes:
        model: a model file (YAML, URDF, xacro) or a generated directory.
        data: the run's CSV file.
        method: ``ols``, ``wls``, ``consistent`` or ``energy``.
        window: the length of the energy balance's windows (s).
        holdout: the last fraction of the run kept for validation.
        cutoff: the low-pass cutoff (Hz) that derives the rates from q when the run has none.
        backend: the backend to load.
        values: parameter values bound before the estimate.
        reading: the robot-file options a model file is read with.
        figure: whether to draw the validation.
    """

    model: str
    data: str
    method: str = "wls"
    window: float = 0.05
    holdout: float = 0.25
    cutoff: float | None = None
    backend: str = "numpy"
    values: Mapping[str, float] = field(default_factory=dict)
    reading: Mapping[str, Any] = field(default_factory=dict)
    figure: bool = True


@dataclass(frozen=True)
class Identified:
    """What :func:`identify` found: the model's name and the output directory's files by name (estimate.json,
    estimate.csv, summary.txt; validation.png; identified.yaml and identified.urdf where a model file was given)."""

    name: str
    files: dict[str, str | bytes]


def _quiet(_title: str) -> AbstractContextManager[Callable[..., None]]:
    """A progress display that shows nothing."""
    return nullcontext(lambda *_args, **_kwargs: None)


def identify(request: IdentifyRequest, display: Callable[[str], AbstractContextManager[Any]] = _quiet) -> Identified:
    """Identify the device of ``request.model`` from the run ``request.data`` (module docstring).

    Args:
        display: the progress display (given a title, a context manager whose value takes each stage).

    Raises:
        ValueError: the model cannot be identified so (its message names the file and what to derive), the run
            is refused (:class:`symkin.identification.estimation.DataError`: file, row and column), or it does not
            excite the base parameters.
    """
    from symkin.identification import estimation
    from symkin.identification.device_regressors import run_regressors

    reading = dict(request.reading) if model_files.is_model_file(request.model) else {}
    source = _model_file(request.model, reading)
    needed = DERIVED["identify energy" if request.method == "energy" else "identify"]
    model = model_files.generated_model(request.model, request.backend, *needed, reading=reading,
                                        display=None if display is _quiet else display)
    model = model.bind(**request.values) if request.values else model
    model = run_regressors(model, request.data, request.model)
    coordinates = model.info.coordinate_names
    data = estimation.read_measurements(request.data, coordinates, request.cutoff)
    fit, held = data.split(request.holdout)
    names = model.info.functions["base_regressor"].outputs["pi_b"]
    with display(model.name) as progress:
        progress(f"estimating {len(names)} base parameters from {len(fit.time)} samples")
        Y_b, pi_model = model.base_regressor(fit.q, fit.qd, fit.qdd)
        writes_model = source is not None
        # the standard regressor over the fit, evaluated once: for the consistent and energy estimates and the
        # model file
        needs_Y = request.method in ("consistent", "energy") or writes_model
        Y, pi = _regressor(model, fit, request.method) if needs_Y else (None, None)
        K = _combinations(Y, Y_b) if request.method == "energy" or writes_model else None
        if request.method == "energy":
            found = _energy(model, fit, Y, Y_b, K, names, request.window)
        else:
            found = estimation.least_squares(Y_b, fit.tau, names, "ols" if request.method == "ols" else "wls")
        predict = None
        if len(held.time):
            Y_held = model.base_regressor(held.q, held.qd, held.qdd)[0]
            predict = Y_held @ found.values
        standard = None
        if request.method == "consistent":
            progress("estimating physically consistent standard parameters")
            standard = _consistent(model, Y, pi, fit, found)
            if len(held.time):
                predict = model.regressor(held.q, held.qd, held.qdd)[0] @ standard.values
        check = None if predict is None else estimation.validation_of(predict, held.tau)
        updated, line = None, None
        if writes_model:
            progress("writing the model file with the identified values")
            file_values = _file_values(source, model, Y, K, pi, fit, found, standard)
            updated, line = _updated_model(request, source, model, file_values, found, standard)
        files = _report(request, model, data, found, pi_model[0], check, standard, line)
        if updated is not None:
            files["identified.yaml"] = updated.text
            if updated.urdf is not None:
                files["identified.urdf"] = updated.urdf
        if check is not None and predict is not None and request.figure:
            progress("drawing the validation")
            files["validation.png"] = estimation.validation_figure_png(
                held.time, held.tau, predict, coordinates,
                ["N*m" if c.revolute else "N" for c in model.info.coordinates],
                f"{model.name}: held-out efforts, measured and predicted ({request.method})")
    return Identified(model.name, files)


def _model_file(path: str, reading: dict):
    """The :class:`~symkin.model.schema.Model` of MODEL when it is a model file (read once, with the robot-file
    options ``reading``: it is rewritten into identified.yaml), None for a generated directory."""
    if not model_files.is_model_file(path):
        return None
    from symkin.model import load_model

    return load_model(path, **reading)


def _regressor(model, fit, method: str) -> tuple[np.ndarray, np.ndarray]:
    """Y and the model's pi over the fit part of the run (the standard parameters' regressor)."""
    if "regressor" not in model.info.functions:
        raise ValueError(f"{model.name}: --method {method} needs the regressor; derive it (--only regressor,"
                         f"base_regressor{',energy_regressor' if method == 'energy' else ''}) or give the model file")
    return model.regressor(fit.q, fit.qd, fit.qdd)


def _combinations(Y, Y_b):
    """K with Y = Y_b K over the fit (fitted once: the energy estimate and identified.yaml both use it)."""
    from symkin.identification import implied_parameters

    return implied_parameters.combinations(Y, Y_b)


def _energy(model, fit, Y, Y_b, K, names, window: float):
    """The base parameters from the energy balance over windows of the fit part of the run (Gautier 1997)."""
    from symkin.identification import estimation

    if "energy_regressor" not in model.info.functions:
        outputs = ",".join(DERIVED["identify energy"].required_of(model.info.functions))
        raise ValueError(f"{model.name}: --method energy needs the energy regressor; derive it (--only {outputs}) or "
                         "give the model file")
    return estimation.energy_least_squares(fit, Y, model.energy_regressor(fit.q, fit.qd)[0], Y_b, K,
                                               model.info.functions["regressor"].outputs["pi"], names, window)


def _consistent(model, Y, pi, fit, found, in_file=None):
    """The consistent standard parameters from the fit part of the run, weighted as the WLS estimate; given
    ``in_file`` (a :class:`~symkin.identification.identified_model.Held` and the consistent estimate), the consistent
    values a model file holds, started from those nearest the estimate."""
    from symkin.identification import consistent, estimation

    weights = 1.0 / np.where(found.joint_std > 0, found.joint_std, 1.0)
    triangle, target = estimation.weighted_triangle(Y, fit.tau, weights)
    if in_file is None:
        return consistent.estimate(triangle, target, model.info.functions["regressor"].outputs["pi"], pi[0])
    held, standard = in_file
    return consistent.estimate(triangle @ held.T, target - triangle @ held.fixed, held.names, held.values_of(pi[0]),
                               start=held.values_of(standard.values))


def _file_values(source, model, Y, K, pi, fit, found, standard) -> tuple[np.ndarray, np.ndarray, str]:
    """What identified.yaml is written from (:func:`symkin.identification.implied_parameters.file_values`), the values a
    model file holds refitted by the consistent estimate where the run asked for it."""
    from symkin.identification import implied_parameters

    def consistent_held(held):
        return _consistent(model, Y, pi, fit, found, (held, standard)).values

    return implied_parameters.file_values(source, model.info.functions["regressor"].outputs["pi"], K, pi[0], found,
                                          standard, consistent_held)


def _updated_model(request: IdentifyRequest, source, model, file_values, found, standard):
    """identified.yaml: the model file with what the run identifies replaced (``file_values``: :func:`_file_values`;
    of a URDF or xacro file its chain as a symkin model, and identified.urdf), and the summary's line on it (or
    why not).

    Returns:
        (the :class:`~symkin.identification.identified_model.UpdatedModel` or None, the summary's line).
    """
    from symkin.identification import identified_model

    estimate, identified, held_note = file_values
    names = model.info.functions["regressor"].outputs["pi"]
    record = {"method": found.method if standard is None else "consistent", "data": Path(request.data).name,
              "samples": found.samples}
    try:
        updated = identified_model.updated_model(request.model, source, names, estimate, identified, record,
                                                 dict(request.values), dict(request.reading))
    except identified_model.NotUpdated as why:
        return None, f"no identified.yaml: {why}"
    also = "" if updated.urdf is None else "; identified.urdf: the same as a URDF"
    return updated, (f"identified.yaml: {request.model} with the bodies of {', '.join(updated.links) or 'no link'} "
                     f"and the drives of {', '.join(updated.joints) or 'no joint'} identified "
                     f"({len(updated.identified)} standard parameters){also}{held_note}")


def _report(request: IdentifyRequest, model, data, found, pi_model, check, standard=None, model_line=None) -> dict[str, str | bytes]:
    """estimate.json, estimate.csv and summary.txt (ending with ``model_line``, on identified.yaml, if given)."""
    rows = [{"name": n, "value": float(v), "std": float(s), "relative_std": float(r) if math.isfinite(r) else None,
             "model": float(m)}
            for n, v, s, r, m in zip(found.names, found.values, found.std, found.relative_std, pi_model)]
    record = {"model": model.name, "data": str(request.data), "method": found.method, "samples": found.samples,
              "rates": data.rates, "condition": found.condition,
              "joint_residual_std": dict(zip(model.info.coordinate_names, map(float, found.joint_std))),
              "parameters": rows}
    how = found.method
    if found.method == "energy":
        record["window"] = request.window
        how = f"energy balance over windows of {request.window:g} s"
    lines = [f"{model.name}: {len(found.names)} base parameters from {found.samples} samples of {request.data} "
             f"({how}, condition {found.condition:.3g}; rates {data.rates})",
             f"  {'parameter':<22} {'estimate':>13} {'std':>11} {'std %':>8} {'model':>13}"]
    for row in rows:
        lines.append(f"  {row['name']:<22} {row['value']:>13.6g} {row['std']:>11.3g} "
                     f"{_percent(row['relative_std']):>8} {row['model']:>13.6g}")
    if check is not None:
        record["validation"] = {"samples": check.samples, "rms": dict(zip(model.info.coordinate_names,
                                                                           map(float, check.rms))),
                                "relative_rms": dict(zip(model.info.coordinate_names, map(float, check.relative)))}
        lines.append(f"  validation on the last {check.samples} samples: torque RMS "
                     + ", ".join(f"{n} {r:.3g} ({100 * rel:.2g} %)" for n, r, rel in
                                 zip(model.info.coordinate_names, check.rms, check.relative)))
    if standard is not None:
        record["standard"] = {"parameters": dict(zip(standard.names, map(float, standard.values))),
                              "smallest_pseudo_inertia_eigenvalue": [float(np.linalg.eigvalsh(J)[0])
                                                                     for J in standard.pseudo_inertias()],
                              "data_cost": standard.cost, "least_squares_cost": standard.best_cost,
                              "solver": {"converged": standard.converged, "evaluations": standard.evaluations,
                                         "optimality": standard.optimality}}
        lines.append(f"  physically consistent standard parameters (every link's pseudo-inertia positive definite): "
                     f"weighted data cost {standard.cost:.4g} against {standard.best_cost:.4g} unconstrained; "
                     f"solver {standard.solver_text()}")
    if model_line is not None:
        lines.append(f"  {model_line}")
    csv_lines = ["name,value,std,relative_std,model"] + [
        f"{r['name']},{r['value']!r},{r['std']!r},{r['relative_std']!r},{r['model']!r}" for r in rows]
    return {"estimate.json": json.dumps(record, indent=2, allow_nan=False) + "\n",
            "estimate.csv": "\n".join(csv_lines) + "\n", "summary.txt": "\n".join(lines) + "\n"}


def _percent(relative: float | None) -> str:
    return "-" if relative is None else f"{100 * relative:.3g}"

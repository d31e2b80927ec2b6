"""``symkin identify MODEL DATA.csv``: a device's base parameters from a run (symkin.identification.estimation)."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.analysis.needs import DERIVED
from symkin.cli.progress import Progress
from symkin.cli.urdf_args import add_urdf_arguments, urdf_options

def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "identify", help="identify a device's base parameters from a measured run (CSV of q, tau)",
        description="Estimate the base parameters pi_b (the identifiable combinations of the links' masses, first "
                    "moments and inertias, the rotor inertias and the joints' friction; symkin quantities: "
                    "base_regressor) from a run recorded on the device: least squares on tau = Y_b(q, qd, qdd) pi_b "
                    "over the samples, with each estimate's standard deviation, validated on the last --holdout "
                    "part of the run (torque RMS per joint). DATA.csv has a column t (s) and, per coordinate, "
                    "q_<name>, tau_<name> and optionally qd_<name>, qdd_<name> (without them, --cutoff derives the "
                    "rates from q by a zero-phase low-pass filter). Writes estimate.json, estimate.csv, "
                    "summary.txt and validation.png (measured and predicted efforts) into the output directory "
                    "(replaced as a whole), and given a model file identified.yaml, the model with the identified "
                    "values (given a URDF or xacro file also identified.urdf; of a parallel model, the values its "
                    "file holds: one rotor for all actuators). A parallel model's run records its actuators (and a "
                    "hybrid device's wrist joints): each sample's platform pose is fk(q) (without a closed form, as "
                    "the Stewart-Gough platform's, by Newton's method from the home pose). Bad data are refused "
                    "with the file, row and column, and nothing is written.",
        epilog="e.g. symkin identify models/planar_2r.yaml run.csv --method wls -o out/identify/planar_2r")
    analysis_args.add_model_arguments(p)
    p.add_argument("data", metavar="DATA.csv", help="the measured run")
    p.add_argument("--method", choices=("ols", "wls", "consistent", "energy"), default="wls",
                   help="ordinary least squares, or weighted by each joint's residual, on the base parameters; or "
                        "'consistent': also the standard parameters, every body (a link; a parallel model's platform "
                        "and arms) a physical rigid body (positive definite pseudo-inertia), a rod's end masses and "
                        "the drives' inertia and friction non-negative, nearest the model's values among the fits; "
                        "or 'energy': least squares on the energy balance over windows of the run (the work of tau "
                        "against the change of the energy and the friction's loss; no accelerations enter the "
                        "estimate) (default: %(default)s)")
    p.add_argument("--window", type=float, default=0.05, metavar="S",
                   help="--method energy: the length of the windows of the energy balance, one equation each "
                        "(default: %(default)s s)")
    p.add_argument("--holdout", type=float, default=0.25, metavar="F",
                   help="the last fraction of the run kept for validation (default: %(default)s; 0: none)")
    p.add_argument("--cutoff", type=float, metavar="HZ",
                   help="low-pass cutoff that derives qd and qdd from q when the file has no rate columns")
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/identify/MODEL)")
    p.add_argument("--no-figure", action="store_true", help="write the numbers only")
    add_urdf_arguments(p)
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    from symkin.identification import estimation
    from symkin.identification.device_regressors import run_regressors

    start = time.perf_counter()
    try:
        if not 0.0 <= args.holdout < 1.0:
            raise ValueError(f"--holdout must lie in [0, 1), got {args.holdout:g}")
        if not args.window > 0:
            raise ValueError(f"--window must be a positive number of seconds, got {args.window:g}")
        reading = urdf_options(args, args.model) if model_files.is_model_file(args.model) else {}
        source = _model_file(args.model, reading)
        needed = DERIVED["identify energy" if args.method == "energy" else "identify"]
        model = model_files.generated_model(args.model, args.backend, *needed, reading=reading, display=Progress)
        values = analysis_args.parse_assignments(args.assignments)
        model = model.bind(**values) if values else model
        model = run_regressors(model, args.data, args.model)
        coordinates = model.info.coordinate_names
        data = estimation.read_measurements(args.data, coordinates, args.cutoff)
        fit, held = data.split(args.holdout)
        names = model.info.functions["base_regressor"].outputs["pi_b"]
        with Progress(model.name) as progress:
            progress(f"estimating {len(names)} base parameters from {len(fit.time)} samples")
            Y_b, pi_model = model.base_regressor(fit.q, fit.qd, fit.qdd)
            writes_model = model_files.is_model_file(args.model)
            # the standard regressor over the fit, evaluated once: for the consistent and energy estimates and the
            # model file
            needs_Y = args.method in ("consistent", "energy") or writes_model
            Y, pi = _regressor(model, fit, args.method) if needs_Y else (None, None)
            K = _combinations(Y, Y_b) if args.method == "energy" or writes_model else None
            if args.method == "energy":
                found = _energy(model, fit, Y, Y_b, K, names, args.window)
            else:
                found = estimation.least_squares(Y_b, fit.tau, names, "ols" if args.method == "ols" else "wls")
            predict = None
            if len(held.time):
                Y_held = model.base_regressor(held.q, held.qd, held.qdd)[0]
                predict = Y_held @ found.values
            standard = None
            if args.method == "consistent":
                progress("estimating physically consistent standard parameters")
                standard = _consistent(model, Y, pi, fit, found)
                if len(held.time):
                    predict = model.regressor(held.q, held.qd, held.qdd)[0] @ standard.values
            check = None if predict is None else estimation.validation_of(predict, held.tau)
            updated, line = None, None
            if writes_model:
                progress("writing the model file with the identified values")
                file_values = _file_values(source, model, Y, K, pi, fit, found, standard)
                updated, line = _updated_model(args, source, model, file_values, found, standard, values,
                                               reading)
            files = _report(args, model, data, found, pi_model[0], check, standard, line)
            if updated is not None:
                files["identified.yaml"] = updated.text
                if updated.urdf is not None:
                    files["identified.urdf"] = updated.urdf
            if check is not None and predict is not None and not args.no_figure:
                progress("drawing the validation")
                files["validation.png"] = estimation.validation_figure_png(
                    held.time, held.tau, predict, coordinates,
                    ["N*m" if c.revolute else "N" for c in model.info.coordinates],
                    f"{model.name}: held-out efforts, measured and predicted ({args.method})")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    analysis_args.write_outputs(Path(args.out or f"out/identify/{model.name}"), files, start)
    return 0


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
    ``in_file`` (a :class:`~symkin.identification.implied_parameters.Held` and the consistent estimate), the consistent
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


def _updated_model(args: argparse.Namespace, source, model, file_values, found, standard, values: dict[str, float],
                   reading: dict):
    """identified.yaml: the model file with what the run identifies replaced (``file_values``: :func:`_file_values`;
    of a URDF or xacro file its chain as a symkin model, and identified.urdf), and the summary's line on it (or
    why not); ``reading``: the robot-file options the model file was read with.

    Returns:
        (the :class:`~symkin.identification.identified_model.UpdatedModel` or None, the summary's line).
    """
    from symkin.identification import identified_model

    estimate, identified, held_note = file_values
    names = model.info.functions["regressor"].outputs["pi"]
    record = {"method": found.method if standard is None else "consistent", "data": Path(args.data).name,
              "samples": found.samples}
    try:
        updated = identified_model.updated_model(args.model, source, names, estimate, identified, record, values,
                                                 reading)
    except identified_model.NotUpdated as why:
        return None, f"no identified.yaml: {why}"
    also = "" if updated.urdf is None else "; identified.urdf: the same as a URDF"
    return updated, (f"identified.yaml: {args.model} with the bodies of {', '.join(updated.links) or 'no link'} "
                     f"and the drives of {', '.join(updated.joints) or 'no joint'} identified "
                     f"({len(updated.identified)} standard parameters){also}{held_note}")


def _report(args, model, data, found, pi_model, check, standard=None, model_line=None) -> dict[str, str | bytes]:
    """estimate.json, estimate.csv and summary.txt (ending with ``model_line``, on identified.yaml, if given)."""
    rows = [{"name": n, "value": float(v), "std": float(s), "relative_std": float(r) if math.isfinite(r) else None,
             "model": float(m)}
            for n, v, s, r, m in zip(found.names, found.values, found.std, found.relative_std, pi_model)]
    record = {"model": model.name, "data": str(args.data), "method": found.method, "samples": found.samples,
              "rates": data.rates, "condition": found.condition,
              "joint_residual_std": dict(zip(model.info.coordinate_names, map(float, found.joint_std))),
              "parameters": rows}
    how = found.method
    if found.method == "energy":
        record["window"] = args.window
        how = f"energy balance over windows of {args.window:g} s"
    lines = [f"{model.name}: {len(found.names)} base parameters from {found.samples} samples of {args.data} "
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
                              "data_cost": standard.cost, "least_squares_cost": standard.best_cost}
        lines.append(f"  physically consistent standard parameters (every link's pseudo-inertia positive definite): "
                     f"weighted data cost {standard.cost:.4g} against {standard.best_cost:.4g} unconstrained")
    if model_line is not None:
        lines.append(f"  {model_line}")
    csv_lines = ["name,value,std,relative_std,model"] + [
        f"{r['name']},{r['value']!r},{r['std']!r},{r['relative_std']!r},{r['model']!r}" for r in rows]
    return {"estimate.json": json.dumps(record, indent=2, allow_nan=False) + "\n",
            "estimate.csv": "\n".join(csv_lines) + "\n", "summary.txt": "\n".join(lines) + "\n"}


def _percent(relative: float | None) -> str:
    return "-" if relative is None else f"{100 * relative:.3g}"

"""Tables and a figure of a :class:`~symkin.stability.harness.StabilityRun`."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import numpy as np

from symkin.atomic import replace_file
from symkin.text_table import format_table
from symkin.stability.harness import BOUND, KAPPA_LIMIT, SOLVE_ULPS, StabilityRun

KAPPA_BINS = (1.0, 1e1, 1e2, 1e3, 1e6, 1e9, 1e12, math.inf)
SHOWN_STEPS = (1e-1, 1e-3, 1e-6, 1e-9, 1e-12)


def _e(value: float) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return "inf" if math.isinf(value) else f"{value:.1e}"


def _bin_label(lo: float, hi: float) -> str:
    return f"[{lo:.0e}, {'inf' if math.isinf(hi) else f'{hi:.0e}'})"


def kappa_table(run: StabilityRun) -> str:
    """Largest normwise error per quantity in each kappa bin (float64: random, singular, scale)."""
    records = [r for r in run.records if r.family != "float32"]
    rows = []
    for lo, hi in zip(KAPPA_BINS[:-1], KAPPA_BINS[1:]):
        inside = [r for r in records if lo <= r.kappa < hi or (lo == 1.0 and r.kappa < 1.0)]
        if not inside:
            continue
        row = [_bin_label(lo, hi), len({(r.family, r.label, r.parameter, r.kappa) for r in inside})]
        row += [_e(max((r.error for r in inside if r.quantity == q), default=float("nan"))) for q in run.quantities]
        rows.append(row)
    return format_table(["kappa", "states"] + list(run.quantities), rows)


def scale_table(run: StabilityRun) -> str:
    """Largest normwise error per quantity at each length scale (float64)."""
    records = run.select("scale")
    rows = []
    for scale in sorted({r.parameter for r in records}):
        at = [r for r in records if r.parameter == scale]
        rows.append([f"{scale:g}", _e(max(r.kappa for r in at))]
                    + [_e(max(r.error for r in at if r.quantity == q)) for q in run.quantities])
    return format_table(["length scale", "max kappa"] + list(run.quantities), rows)


def path_table(run: StabilityRun) -> str:
    """Kappa and largest error (over quantities) along each path into a singularity."""
    records = run.select("singular")
    rows = []
    for path in run.paths:
        for t in SHOWN_STEPS:
            at = [r for r in records if r.label == path.label and math.isclose(r.parameter, t)]
            if at:
                worst = max(at, key=lambda r: r.error)
                jacobian = next((r for r in at if r.quantity == "jacobian"), at[0])
                rows.append([path.label, f"{t:.0e}", _e(jacobian.kappa), _e(worst.error), worst.quantity])
    return format_table(["path", "t", "kappa(J)", "max error", "worst quantity"], rows)


def float32_table(run: StabilityRun) -> str:
    """float32 evaluation of the optimized code: median and largest error, in units of float32 eps."""
    eps32 = float(np.finfo(np.float32).eps)
    rows = []
    for q in run.quantities:
        errors = np.array([r.error for r in run.select("float32", q)])
        rows.append([q, _e(float(np.median(errors))), _e(float(errors.max())), f"{errors.max() / eps32:.1f}"])
    return format_table(["quantity", "median error", "max error", "max / eps32"], rows)


def formula_table(run: StabilityRun) -> str:
    blocks = []
    for f in run.formulas:
        rows = [[f"{t:.0e}", _e(a), _e(b)] + ([_e(c)] if f.bound is not None else [])
                for t, a, b, c in zip(f.steps, f.textbook, f.symkin,
                                      f.bound if f.bound is not None else [None] * len(f.steps))]
        headers = [f"{f.angle} = t", "textbook acos", "symkin atan2"] + (["eps * cond"] if f.bound is not None else [])
        blocks.append(f"  {f.title}: absolute error (rad)\n" + format_table(headers, rows))
    return "\n".join(blocks)


def report_text(run: StabilityRun) -> str:
    """The whole text report."""
    passed, worst = run.acceptance()
    random = run.select("random")
    parts = [
        f"numerical stability of {run.model}: generated numpy code against a 50-digit reference "
        f"(normwise relative error |f - f_ref| / |f_ref| per function; kappa = condition number of the matrix "
        f"the function inverts: M for forward_dynamics, J for tcp_force and operational_space; "
        f"of the task Jacobian J for the others)",
        f"quantities: {', '.join(run.quantities)}"
        + (f"; not derivable: {', '.join(run.skipped)}" if run.skipped else ""),
        f"records: {len(run.records)} ({len(random)} random, {len(run.select('singular'))} singular, "
        f"{len(run.select('scale'))} scaled, {len(run.select('float32'))} float32)",
        "",
        "error vs kappa (float64)",
        kappa_table(run),
        "",
        "error vs length scale (all length parameters multiplied; float64)",
        scale_table(run),
        "",
        "paths into singularities (x_j = x* + t: a joint of a serial chain, a task coordinate of a parallel "
        "mechanism, times its characteristic length)",
        path_table(run) if run.paths else "  (no singular configuration found)",
        "",
        "float32 (optimized IR printed by the numpy printer, evaluated on float32 arrays)",
        float32_table(run),
    ]
    if run.formulas:
        parts += ["", "closed-form IK near singularities", formula_table(run)]
    nonfinite = [r for r in run.records if math.isinf(r.error)]
    parts += ["", f"non-finite values: {len(nonfinite)}",
              f"acceptance: every error where kappa < {KAPPA_LIMIT:g} <= max({BOUND:g}, {SOLVE_ULPS:g} kappa eps) "
              f"(largest {worst:.2e}): {'PASS' if passed else 'FAIL'}"]
    return "\n".join(parts)


def write_csv(run: StabilityRun, path: Path) -> None:
    """Every record, one row each, written atomically (the previous file or the complete new one)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["model", "quantity", "family", "label", "parameter", "kappa", "error"])
    for r in run.records:
        writer.writerow([run.model, r.quantity, r.family, r.label, repr(r.parameter), repr(r.kappa), repr(r.error)])
    replace_file(Path(path), buffer.getvalue())


def write_figure(run: StabilityRun, path: Path) -> None:
    """Error vs kappa (float64 and float32), error vs length scale and the IK formulas, as a PNG/PDF/SVG (by
    the suffix), written atomically; drawn on a ``matplotlib.figure.Figure``, so the caller's backend and
    pyplot state (a notebook's) are left alone."""
    from matplotlib.figure import Figure

    panels = 3 + (1 if run.formulas else 0)
    fig = Figure(figsize=(4.6 * panels, 4.2))
    axes = fig.subplots(1, panels)
    floor = 1e-18
    ax = axes[0]
    for q in run.quantities:
        rs = [r for r in run.records if r.quantity == q and r.family != "float32" and math.isfinite(r.kappa)]
        ax.loglog([r.kappa for r in rs], [max(r.error, floor) for r in rs], ".", ms=3, label=q)
    kappas = np.logspace(0, 13, 50)
    ax.loglog(kappas, kappas * np.finfo(float).eps, "k:", lw=1, label="kappa * eps")
    ax.axhline(BOUND, color="r", lw=0.8)
    ax.axvline(KAPPA_LIMIT, color="r", lw=0.8, ls="--")
    ax.set(xlabel="kappa (task Jacobian)", ylabel="normwise relative error", title=f"{run.model}: float64")
    ax.legend(fontsize=7)
    ax = axes[1]
    for q in run.quantities:
        rs = run.select("float32", q)
        ax.loglog([r.kappa for r in rs], [max(r.error, floor) for r in rs], ".", ms=4, label=q)
    ax.axhline(float(np.finfo(np.float32).eps), color="k", lw=0.8, ls=":")
    ax.set(xlabel="kappa", ylabel="normwise relative error", title="float32 (optimized IR)")
    ax = axes[2]
    scales = sorted({r.parameter for r in run.select("scale")})
    for q in run.quantities:
        worst = [max(r.error for r in run.select("scale", q) if r.parameter == s) for s in scales]
        ax.loglog(scales, [max(w, floor) for w in worst], "o-", ms=3, label=q)
    ax.axhline(BOUND, color="r", lw=0.8)
    ax.set(xlabel="length scale", ylabel="max normwise relative error", title="length scale (float64)")
    if run.formulas:
        ax = axes[3]
        for f in run.formulas:
            ax.loglog(f.steps, np.maximum(f.textbook, floor), "s-", ms=3, label=f"{f.angle}: textbook acos")
            ax.loglog(f.steps, np.maximum(f.symkin, floor), "o-", ms=3, label=f"{f.angle}: symkin atan2")
            if f.bound is not None:
                ax.loglog(f.steps, np.maximum(f.bound, floor), "k:", label="eps * condition number")
        ax.set(xlabel="distance to the singular value (rad)", ylabel="absolute error (rad)",
               title="closed-form IK near a singularity")
        ax.legend(fontsize=7)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format=Path(path).suffix.lstrip(".").lower() or "png", dpi=110)
    replace_file(Path(path), buffer.getvalue())

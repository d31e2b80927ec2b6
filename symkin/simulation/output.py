"""The files of a scenario: figures (matplotlib, Agg, no pyplot), CSV per series, summary.

Everything is rendered in memory and written with :func:`symkin.atomic.replace_directory`,
so the output directory holds either the previous run or the complete new one.
"""

from __future__ import annotations

import io
import re

import numpy as np

from symkin.simulation.scenarios import FigureSpec, ScenarioResult, Series

DPI = 150


def csv_text(model: str, scenario: str, series: Series) -> str:
    """One row per sample, a header of column names with units, a comment line naming the run."""
    names = list(series.columns)
    data = np.column_stack([series.columns[n] for n in names])
    lines = [f"# symkin simulate {model} --scenario {scenario}: {series.label}", ",".join(names)]
    lines += [",".join(f"{v:.10g}" for v in row) for row in data]
    return "\n".join(lines) + "\n"


#: hatches of the joint-stop contact spans, per joint
CONTACT_HATCHES = ("////", "\\\\\\\\", "xxxx", "....", "||||", "----")


def _mark_contacts(ax, series: list[Series], legend: bool) -> None:
    """Shade the joint-stop contacts of every series (grey, one hatch per joint; in the legend
    once per joint and side if ``legend``)."""
    for s in series:
        joints = list(dict.fromkeys(c.joint for c in s.contacts))
        labelled = set()
        for c in s.contacts:
            key = (c.joint, c.side)
            j = joints.index(c.joint)
            label = f"stop contact {c.joint} {c.side}" + (f" ({s.label})" if len(series) > 1 else "")
            ax.axvspan(c.start, c.end, facecolor="0.6", alpha=0.25, hatch=CONTACT_HATCHES[j % len(CONTACT_HATCHES)],
                       edgecolor="0.35", linewidth=0.0, label=None if key in labelled or not legend else label)
            labelled.add(key)


def figure_png(spec: FigureSpec, series: list[Series]) -> bytes:
    """The PNG of :func:`figure_of`."""
    buffer = io.BytesIO()
    figure_of(spec, series).savefig(buffer, format="png", dpi=DPI)
    return buffer.getvalue()


def figure_of(spec: FigureSpec, series: list[Series]):
    """The figure of ``spec``: stacked panels against time, one line per column and series; the
    joint-stop contacts shaded; each panel's legend to its right, where it covers no curve."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(8.5, 2.2 * len(spec.panels) + 0.6), layout="constrained")
    axes = figure.subplots(len(spec.panels), 1, sharex=True, squeeze=False)[:, 0]
    styles = ("-", "--", ":", "-.")
    for ax, (ylabel, columns) in zip(axes, spec.panels):
        for k, s in enumerate(series):
            t = s.columns["t [s]"]
            for j, column in enumerate(columns):
                if column not in s.columns:
                    continue
                name = column.rsplit(" [", 1)[0]
                label = f"{name} ({s.label})" if len(series) > 1 else name
                ax.plot(t, s.columns[column], styles[j % len(styles)], color=f"C{k}" if len(series) > 1 else f"C{j}",
                        label=label, linewidth=1.2)
        _mark_contacts(ax, series, legend=ax is axes[0])
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axes[-1].set_xlabel("t [s]")
    figure.suptitle(spec.title)
    return figure


def _slug(text: str) -> str:
    """'l1 = 10 cm, l2 = 10 cm' -> 'l1=10cm_l2=10cm'."""
    return re.sub(r"[^A-Za-z0-9.=-]+", "_", text.replace(" ", "")).strip("_") or "run"


def scenario_files(model: str, result: ScenarioResult, figures: bool = True) -> dict[str, str | bytes]:
    """{file name: content} of a scenario: CSV per series, summary.txt and the figures."""
    files: dict[str, str | bytes] = {}
    for k, series in enumerate(result.series, start=1):
        files[f"{result.name}-{k}-{_slug(series.label)}.csv"] = csv_text(model, result.name, series)
    files["summary.txt"] = "\n".join(result.summary) + "\n"
    if figures:
        for spec in result.figures:
            files[spec.filename] = figure_png(spec, result.series)
    return files

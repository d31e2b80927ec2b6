"""A maker's published figures beside symkin's (``symkin rate --datasheet SPEC.yaml``, issue 64).

A spec file is data from a stranger, read as a model file is (:func:`symkin.model.yaml_source.read_document`: no
tag runs, size and depth bounded, every value located)::

    device: PHANToM Premium 1.5
    source: SensAble Technologies, product specifications
    figures:
      force_x: {value: 8.5, unit: N, at: home, quote: "maximum exertable force at nominal position"}
      resolution_x: {value: 3.0e-5, unit: m, at: home, quote: "nominal position resolution > 860 dpi"}

Each figure names a measure of the datasheet (as ``symkin rate`` prints it: ``force_x``, ``renderable_stiffness``),
its value in that measure's unit (SI, as the datasheet prints it: a figure in mm is refused with its value in m),
where the maker takes it (``at``: ``home``, the nominal pose, by default; ``worst``, over the workspace) and,
optionally, the maker's words.  The comparison gives symkin's value there and the ratio symkin / maker.  A figure
whose measure the datasheet lists as not rated says why; one that names no measure of the device is an error.

A maker's workspace box may be given beside the figures, its sizes along symkin's x, y and z in m (a datasheet's
width, height and depth set on the device's axes)::

    workspace: {box: [0.191, 0.381, 0.267], unit: m, quote: "381 W x 267 H x 191 D mm"}

and is set beside the usable workspace's shapes (:mod:`symkin.rating.workspace_shapes`): whether it fits inside
(where), the largest box there and the ratio of their volumes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import ModelError, Problem
from symkin.model.yaml_source import Document, read_document, shorten
from symkin.rating.datasheet import Datasheet
from symkin.rating.workspace_shapes import WorkspaceShapes

#: Where a maker takes a figure: at the nominal (home) pose, or its worst over the workspace.
PLACES = ("home", "worst")
TOP_KEYS = ("device", "source", "figures", "workspace")
WORKSPACE_KEYS = ("box", "unit", "quote")
FIGURE_KEYS = ("value", "unit", "at", "quote")
#: Longest maker's text kept (a device name, a source, a quote).
MAX_TEXT = 120


@dataclass(frozen=True)
class MakerFigure:
    """One published figure: the measure, the maker's value and unit, where it is taken and the maker's words."""

    measure: str
    value: float
    unit: str
    at: str
    quote: str


@dataclass(frozen=True)
class MakerBox:
    """A maker's workspace box: its sizes along x, y and z (m) and the maker's words."""

    size: tuple[float, float, float]
    quote: str


@dataclass(frozen=True)
class MakerSheet:
    """A spec file: the device, where its figures come from, the figures in file order and the workspace box."""

    file: str
    device: str
    source: str
    figures: tuple[MakerFigure, ...]
    box: MakerBox | None = None


def _text(value: Any) -> str:
    """A maker's text as one printable line (control characters, line breaks and the like dropped), shortened."""
    return shorten("".join(c for c in str(value) if c.isprintable()), MAX_TEXT)


def read_maker_sheet(path: str | Path) -> MakerSheet:
    """Read and check a spec file (see the module docstring).

    Raises:
        ModelError: the file is unreadable or not of that form; every problem located, with its fix.
    """
    document = read_document(path)
    problems: list[Problem] = []
    data = document.data
    if not isinstance(data, dict):
        raise ModelError([document.problem((), "a spec file is a mapping with device, source and figures",
                                           "write 'device: ...', 'source: ...' and 'figures: {MEASURE: {value: ..., "
                                           "unit: ...}}'")])
    problems += [document.problem((key,), f"unknown key '{shorten(key)}'", f"use only {', '.join(TOP_KEYS)}")
                 for key in data if key not in TOP_KEYS]
    for key in ("device", "source"):
        if not isinstance(data.get(key), str) or not data[key].strip():
            what = "the device" if key == "device" else "the datasheet the figures come from"
            problems.append(document.problem((key,), f"'{key}' must be a non-empty text", f"name {what}"))
    figures = data.get("figures")
    found: list[MakerFigure] = []
    if not isinstance(figures, dict) or not figures:
        problems.append(document.problem(("figures",), "'figures' must be a non-empty mapping of measures",
                                         "write 'figures: {force_x: {value: 8.5, unit: N, at: home}}'"))
    else:
        for name, figure in figures.items():
            checked = _figure(document, str(name), figure, problems)
            if checked is not None:
                found.append(checked)
    box = _workspace_box(document, data["workspace"], problems) if "workspace" in data else None
    if problems:
        raise ModelError(problems)
    return MakerSheet(document.file, _text(data["device"]), _text(data["source"]), tuple(found), box)


def _workspace_box(document: Document, workspace: Any, problems: list[Problem]) -> MakerBox | None:
    """``workspace: {box: [x, y, z], unit: m, quote: ...}`` checked (its problems appended), or None."""
    at = ("workspace",)
    fix = "write 'workspace: {box: [0.191, 0.381, 0.267], unit: m}' (sizes along x, y, z in m)"
    if not isinstance(workspace, dict):
        problems.append(document.problem(at, "the workspace is a mapping", fix))
        return None
    before = len(problems)
    problems += [document.problem(at + (key,), f"unknown key '{shorten(key)}'", f"use only {', '.join(WORKSPACE_KEYS)}")
                 for key in workspace if key not in WORKSPACE_KEYS]
    size = workspace.get("box")
    if not (isinstance(size, list) and len(size) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in size)):
        problems.append(document.problem(at + ("box",), f"the box must be three positive sizes, got '{shorten(size)}'",
                                         fix))
    if workspace.get("unit") != "m":
        problems.append(document.problem(at + ("unit",), f"the box's unit must be m, got "
                                         f"'{shorten(workspace.get('unit'))}'", fix))
    if len(problems) > before or not isinstance(size, list):
        return None
    return MakerBox((float(size[0]), float(size[1]), float(size[2])), _text(workspace.get("quote", "")))


def _figure(document: Document, name: str, figure: Any, problems: list[Problem]) -> MakerFigure | None:
    """One entry of ``figures`` checked (its problems appended), or None."""
    at = ("figures", name)
    if not isinstance(figure, dict):
        problems.append(document.problem(at, "a figure is a mapping", "write {value: NUMBER, unit: UNIT, at: home}"))
        return None
    before = len(problems)
    problems += [document.problem(at + (key,), f"unknown key '{shorten(key)}'", f"use only {', '.join(FIGURE_KEYS)}")
                 for key in figure if key not in FIGURE_KEYS]
    value = figure.get("value")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        problems.append(document.problem(at + ("value",), f"the value must be a finite number, got "
                                         f"'{shorten(value)}'", "write the maker's number in the measure's SI unit"))
    if not isinstance(figure.get("unit"), str):
        problems.append(document.problem(at + ("unit",), "the unit must be a text (the measure's unit as symkin rate "
                                         "prints it)", "write e.g. 'unit: N'"))
    place = figure.get("at", "home")
    if place not in PLACES:
        problems.append(document.problem(at + ("at",), f"'at' must be one of {', '.join(PLACES)}, got "
                                         f"'{shorten(place)}'", "home: the nominal pose; worst: over the workspace"))
    if len(problems) > before:
        return None
    assert isinstance(value, (int, float))  # checked above
    return MakerFigure(name, float(value), figure["unit"], place, _text(figure.get("quote", "")))


@dataclass(frozen=True)
class FigureBeside:
    """A maker's figure beside symkin's value where the maker takes it (None, with ``why``, where not rated)."""

    figure: MakerFigure
    symkin: float | None
    why: str = ""

    @property
    def ratio(self) -> float | None:
        """symkin's value over the maker's (None where either is missing or the maker's is zero)."""
        if self.symkin is None or self.figure.value == 0:
            return None
        return self.symkin / self.figure.value

    def line(self) -> str:
        f = self.figure
        head = f"{f.measure} at {f.at}: "
        said = f" ({f.quote})" if f.quote else ""
        if self.symkin is None:
            return f"{head}maker {f.value:.4g} {f.unit}, symkin not rated ({self.why}){said}"
        ratio = "-" if self.ratio is None else f"{self.ratio:.3g}"
        return f"{head}symkin {self.symkin:.4g} {f.unit}, maker {f.value:.4g} {f.unit}, ratio {ratio}{said}"

    def to_json(self) -> dict[str, Any]:
        f = self.figure
        return {"measure": f.measure, "at": f.at, "unit": f.unit, "maker": f.value, "symkin": self.symkin,
                "ratio": self.ratio, "quote": f.quote, **({"not_rated": self.why} if self.symkin is None else {})}


def compare(sheet: MakerSheet, rated: Datasheet) -> tuple[FigureBeside, ...]:
    """Each figure of ``sheet`` beside the datasheet ``rated``'s value where the maker takes it.

    Raises:
        ValueError: a figure names no measure of the device, or gives it in another unit (naming the file and the
            measures there are).
    """
    rated_or_not = {name: group for group, names in rated.groups.items() for name in names}
    measures = {measure.name: measure for measure in rated.measures}
    out = []
    for figure in sheet.figures:
        if figure.measure not in rated_or_not:
            raise ValueError(f"{sheet.file}: figures.{shorten(figure.measure)}: no such measure of this device; "
                             f"use one of {', '.join(sorted(rated_or_not))}")
        group = rated_or_not[figure.measure]
        if group in rated.skipped:
            out.append(FigureBeside(figure, None, rated.skipped[group]))
            continue
        measure = rated.extremes(measures[figure.measure])
        if figure.unit != measure["unit"]:
            raise ValueError(f"{sheet.file}: figures.{figure.measure}.unit: '{shorten(figure.unit)}' where the "
                             f"datasheet gives {figure.measure} in '{measure['unit']}'; write the maker's value in "
                             f"{measure['unit'] or 'its unit (none)'}")
        value = measure["home"] if figure.at == "home" else measure[measure["worst"]]["value"]
        out.append(FigureBeside(figure, value, "" if value is not None else "not finite at the home pose"))
    return tuple(out)


def box_lines_and_record(box: MakerBox, shapes: WorkspaceShapes) -> tuple[list[str], dict[str, Any]]:
    """The maker's workspace box beside the usable workspace's shapes: whether (and where) it fits, symkin's largest
    box and the ratio of their volumes; summary lines and datasheet.json's record."""
    size = np.array(box.size)
    shown = " x ".join(f"{1e3 * v:.0f}" for v in size)
    said = f" ({box.quote})" if box.quote else ""
    if shapes.not_rated:
        return ([f"workspace box (x, y, z): maker {shown} mm, symkin not rated ({shapes.not_rated}){said}"],
                {"maker_m": list(box.size), "not_rated": shapes.not_rated, "quote": box.quote})
    placed = shapes.place(size)
    largest = shapes.box
    ratio = None if largest is None else largest.volume / float(np.prod(size))
    where = ("no" if placed is None else
             f"yes, at ({', '.join(f'{1e3 * c:.0f}' for c in (placed.lower + placed.upper) / 2)}) mm")
    lines = [f"workspace box (x, y, z): maker {shown} mm{said}; fits inside the usable workspace: {where}",
             "  symkin's largest: " + ("none" if largest is None else
                                       f"{' x '.join(f'{1e3 * v:.0f}' for v in largest.size)} mm, volume ratio "
                                       f"symkin / maker {ratio:.3g}")]
    record = {"maker_m": list(box.size), "quote": box.quote, "fits": placed is not None,
              "placed_centre_m": None if placed is None else ((placed.lower + placed.upper) / 2).tolist(),
              "largest_m": None if largest is None else largest.size.tolist(), "volume_ratio": ratio}
    return lines, record

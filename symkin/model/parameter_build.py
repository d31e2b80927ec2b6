"""The ``parameters:`` section: free parameters with defaults and derived parameters (``expr:``)."""

from __future__ import annotations

from typing import Any

import sympy

from symkin.model import coordinates
from symkin.model.expressions import ExpressionError, parse_expression
from symkin.model.reader import Reader, raw_text
from symkin.model.schema import DerivedParameter, Joint, Parameter
from symkin.model.units import suggestion, unit_of
from symkin.model.yaml_source import KeyPath


def read_parameters(r: Reader, section: Any) -> tuple[tuple[Parameter, ...], tuple[DerivedParameter, ...]]:
    """Free parameters (constant default values) and derived parameters (``expr:``).

    Derived parameters may refer to free and to other derived parameters in any order; they
    are inlined, so they never become inputs of generated functions.  Cycles are errors.
    """
    path: KeyPath = ("parameters",)
    section = r.mapping(path, section, optional=tuple(section) if isinstance(section, dict) else ())
    if section is None:
        return (), ()
    free: list[Parameter] = []
    pending: dict[str, tuple[KeyPath, Any, str, str]] = {}
    for pname, spec in section.items():
        ppath = path + (pname,)
        if r.name(ppath, pname) is None:
            continue
        unit = doc = ""
        value_key = "value"
        if isinstance(spec, dict):
            spec = r.mapping(ppath, spec, optional=("value", "expr", "unit", "doc"))
            if spec is None:
                continue
            unit = r.string(ppath + ("unit",), spec.get("unit", "")) or ""
            doc = r.string(ppath + ("doc",), spec.get("doc", "")) or ""
            if ("value" in spec) == ("expr" in spec):
                r.fail(ppath, "a parameter needs exactly one of 'value:' (a number) or 'expr:' (a formula)",
                       "write 'value: 0.1' for a free parameter or 'expr: l1/2' for a derived one")
                continue
            value_key = "value" if "value" in spec else "expr"
            raw = spec[value_key]
            vpath = ppath + (value_key,)
        else:
            raw, vpath = spec, ppath
        converted = _si_unit(r, ppath, unit, derived=value_key == "expr")
        if converted is None:
            r.invalid.add(pname)
            continue
        unit, factor = converted
        if value_key == "expr":
            pending[pname] = (vpath, raw, unit, doc)
            continue
        value = r.expr(vpath, raw, names={})
        if value is None:
            r.invalid.add(pname)
            continue
        value = value * factor
        symbol = sympy.Symbol(pname, real=True)
        if unit:
            r.dimensions[symbol] = (unit_of(unit).dimension, unit)  # type: ignore[union-attr]
        free.append(Parameter(pname, symbol, value, unit, doc))
        r.names[pname] = symbol
        r.defaults[symbol] = value
    derived = _resolve_derived(r, pending)
    return tuple(free), derived


def _si_unit(r: Reader, path: KeyPath, text: str, derived: bool) -> tuple[str, sympy.Expr] | None:
    """(the unit the parameter carries, the exact factor of its value to SI) for the written ``unit:``
    (:mod:`symkin.model.units`); None, with a located problem, for an unknown unit or a non-SI unit on a
    derived parameter (its formula computes in SI from the other parameters)."""
    if not text:
        return "", sympy.Integer(1)
    known = unit_of(text)
    if known is None:
        r.fail(path + ("unit",), f"unknown unit '{text[:40]}'", suggestion(text))
        return None
    if known.factor == 1:
        return text, sympy.Integer(1)  # SI: the text as written (kg*m^2 or kg m^2)
    if derived:
        r.fail(path + ("unit",), f"a derived parameter's formula computes in SI units from the other parameters, "
               f"so its unit cannot be '{text}'", f"write unit: {known.si}, and the formula's result in {known.si}")
        return None
    return known.si, known.factor


def _resolve_derived(r: Reader, pending: dict[str, tuple[KeyPath, Any, str, str]]) -> tuple[DerivedParameter, ...]:
    """Parse derived parameters in dependency order; report cycles and unknown names."""
    resolved: list[DerivedParameter] = []
    waiting = dict(pending)
    while waiting:
        progress = False
        blocked: dict[str, str] = {}
        for pname, (vpath, raw, unit, doc) in list(waiting.items()):
            try:
                definition = parse_expression(raw_text(r, vpath, raw), r.names)
            except ExpressionError as err:
                if err.undefined_name in waiting:
                    blocked[pname] = err.undefined_name
                    continue
                r.expr(vpath, raw)  # records the located problem
                r.invalid.add(pname)
                del waiting[pname]
                progress = True
                continue
            resolved.append(DerivedParameter(pname, definition, unit, doc))
            r.names[pname] = definition
            del waiting[pname]
            progress = True
        if not progress:
            for pname in sorted(blocked):
                cycle = _cycle_from(pname, blocked)
                r.fail(waiting[pname][0], f"derived parameters form a cycle: {' -> '.join(cycle)}",
                       "define at least one parameter of the cycle by a number ('value:')")
            break
    return tuple(resolved)


def _cycle_from(start: str, edges: dict[str, str]) -> list[str]:
    seen = [start]
    node = edges.get(start)
    while node is not None and node not in seen:
        seen.append(node)
        node = edges.get(node)
    return seen + ([node] if node is not None else [])


def check_name_clashes(r: Reader, parameters: tuple[Parameter, ...], derived: tuple[DerivedParameter, ...],
                        joints: tuple[Joint, ...]) -> None:
    taken = {p.name for p in parameters} | {p.name for p in derived}
    for i, joint in enumerate(joints):
        for symbol in coordinates.all_symbol_names(joint.name):
            if symbol in taken:
                r.fail(("parameters", symbol), f"parameter '{symbol}' clashes with the symbol '{symbol}' of "
                                               f"joint '{joint.name}' (joint {i + 1})",
                       f"rename the parameter or the joint '{joint.name}'")

"""Column maps through the optimizer: their values share the function's CSE, their columns are unrolled after it.

A spec's column map (:class:`~symkin.ir.spec.ColumnMap`) reads values of the function - the factors of a solve and
one column of right-hand sides per column - and gives results the outputs use.  :func:`with_map_values` hands those
values to the passes and the CSE as one more output (so they are folded and shared like any other expression, and
the map's results stay opaque symbols there); :func:`unroll_maps` then takes that output off again, writes every
column's copy of the body into the temporaries (a column's numbers folded into its copy: a column of the identity
costs what its nonzeros need) and records the run of temporaries as a :class:`~symkin.ir.spec.MapBlock`, which a
backend with loops prints as one loop (:mod:`symkin.backends.c.emit`) and every other reads as straight-line code.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterator

import sympy

from symkin.ir.opcount import op_count
from symkin.ir.spec import ColumnMap, FunctionSpec, MapBlock, OptimizedFunction, OutputSpec
from symkin.optimize.cse import TEMPORARY_PREFIX, used_by

#: Name of the output that carries the maps' values through the passes (removed again by :func:`unroll_maps`).
MAP_VALUES = "_map_values"


def with_map_values(spec: FunctionSpec) -> FunctionSpec:
    """``spec`` without its maps, their values (:meth:`ColumnMap.values`, map by map) as a last output.

    Raises:
        ValueError: a map's values read a map's results (maps run after every other value, not one another).
    """
    values = [v for m in spec.maps for v in m.values()]
    targets = {t for m in spec.maps for column in m.targets for t in column}
    if any(v.free_symbols & targets for v in values):
        raise ValueError(f"{spec.name}: a column map's values read a column map's results; maps do not chain")
    carrier = OutputSpec(MAP_VALUES, sympy.ImmutableMatrix(len(values), 1, values), "the column maps' values",
                         shape=(len(values),))
    return dataclasses.replace(spec, outputs=spec.outputs + (carrier,), maps=())


def _fresh_names(temporaries: tuple[tuple[sympy.Symbol, sympy.Expr], ...]) -> Iterator[sympy.Symbol]:
    """Temporary symbols numbered after the highest ``_x<k>`` of ``temporaries``."""
    numbers = [int(s.name[len(TEMPORARY_PREFIX):]) for s, _ in temporaries
               if s.name.startswith(TEMPORARY_PREFIX) and s.name[len(TEMPORARY_PREFIX):].isdigit()]
    return (sympy.Symbol(f"{TEMPORARY_PREFIX}{k}", real=True) for k in itertools.count(max(numbers, default=-1) + 1))


def _placed(temporaries: tuple[tuple[sympy.Symbol, sympy.Expr], ...], values: list[sympy.Expr],
            names: Iterator[sympy.Symbol]) -> tuple[list[tuple[sympy.Symbol, sympy.Expr]], list[sympy.Expr]]:
    """(the temporaries with each of ``values`` that is no symbol or number named right after the last temporary it
    reads, the values as atoms): a value is not held live until the maps run (a derivative's entry is written as
    soon as its adjoint sweep gives it); equal values share one name."""
    order = {symbol: k for k, (symbol, _) in enumerate(temporaries)}
    after: dict[int, list[tuple[sympy.Symbol, sympy.Expr]]] = {}
    named: dict[sympy.Expr, sympy.Symbol] = {}
    atoms: list[sympy.Expr] = []
    for value in values:
        if value.is_Atom:
            atoms.append(value)
            continue
        if value not in named:
            named[value] = next(names)
            last = max((order[s] for s in value.free_symbols if s in order), default=-1)
            after.setdefault(last, []).append((named[value], value))
        atoms.append(named[value])
    merged = list(after.get(-1, []))
    for k, assignment in enumerate(temporaries):
        merged += [assignment, *after.get(k, [])]
    return merged, atoms


def unroll_maps(function: OptimizedFunction, maps: tuple[ColumnMap, ...]) -> OptimizedFunction:
    """``function`` (optimized from :func:`with_map_values` of a spec with ``maps``) with the maps' values output
    taken off and each map's columns unrolled into temporaries after the rest, a :class:`MapBlock` per map.

    A value that is no symbol or number becomes a temporary before the blocks (:func:`_placed`); in a column's
    copy of the body an assignment that folds to a symbol or a number is substituted into its uses; copies no output
    needs (the upper triangle of an inverse) are dropped.  ``op_counts["cse"]`` counts the unrolled code."""
    *outputs, values_output = function.outputs
    names = _fresh_names(function.temporaries)
    temporaries, values = _placed(function.temporaries, list(values_output), names)

    def named(value: sympy.Expr) -> sympy.Expr:
        if value.is_Atom:
            return value
        symbol = next(names)
        temporaries.append((symbol, value))
        return symbol

    targets: dict[sympy.Symbol, sympy.Expr] = {}
    drafts = []
    position = 0
    for m in maps:
        shared = dict(zip((s for s, _ in m.shared), values[position:]))
        position += len(m.shared)
        count = len(m.columns)
        columns = tuple(tuple(values[position + k * count + c] for k in range(len(m.parameters)))
                        for c in range(count))  # values in the order of ColumnMap.values: parameter by parameter
        position += count * len(m.parameters)
        body = tuple((s, e.xreplace(shared)) for s, e in m.body)
        results = tuple(r.xreplace(shared) for r in m.results)
        start = len(temporaries)
        column_targets = []
        for column, symbols in zip(columns, m.targets):
            local: dict[sympy.Symbol, sympy.Expr] = dict(zip(m.parameters, column))
            for s, e in body:
                local[s] = named(e.xreplace(local))
            column_targets.append(tuple(named(r.xreplace(local)) for r in results))
            targets.update(zip(symbols, column_targets[-1]))
        drafts.append((start, len(temporaries), m.parameters, body, results, columns, tuple(column_targets)))
    final_outputs = tuple(tuple(e.xreplace(targets) for e in entries) for entries in outputs)
    kept = used_by(temporaries, [e for entries in final_outputs for e in entries])
    index = {s: k for k, (s, _) in enumerate(kept)}
    blocks = []
    for first, stop, parameters, block_body, block_results, block_columns, block_targets in drafts:
        inside = [index[s] for s, _ in temporaries[first:stop] if s in index]
        if inside:
            blocks.append(MapBlock(inside[0], inside[-1] + 1, parameters, block_body, block_results, block_columns,
                                   block_targets))
    counts = dict(function.op_counts)
    counts["cse"] = op_count([e for _, e in kept] + [e for entries in final_outputs for e in entries])
    spec = dataclasses.replace(function.spec, outputs=function.spec.outputs[:-1])
    return OptimizedFunction(spec, tuple(kept), final_outputs, counts, tuple(blocks))


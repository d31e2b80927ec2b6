"""Common-subexpression elimination across all outputs of one function."""

from __future__ import annotations

import symengine as se
import sympy
from sympy.core.parameters import distribute

from symkin.expression_dag import free_symbols, name_shared_nodes_of_deep_graphs, post_order
from symkin.ir.spec import FunctionSpec, OptimizedFunction
from symkin.ir.opcount import op_count, spec_op_count
from symkin.symengine_bridge import SympyConverter, to_symengine

#: Prefix of CSE temporaries; model names must start with a letter, so these never clash.
TEMPORARY_PREFIX = "_x"
#: Prefix of the shared nodes named by value numbering before SymEngine's CSE (renamed ``_x..`` after).
VALUE_PREFIX = "_v"

Assignment = tuple[sympy.Symbol, sympy.Expr]

#: Largest function (operations counted as a tree, :func:`~symkin.ir.opcount.spec_op_count`) given
#: to ``sympy.cse``.  sympy's CSE orders arguments by their tree size
#: (``sympy.core.sorting._node_count``, not memoized), so its cost follows the tree: about
#: 4 us per tree operation here, 24 s for the 6-million-operation Jacobian of a 24-joint chain,
#: whose DAG has 979 nodes.  Larger functions go through SymEngine's CSE, whose cost follows the
#: DAG (:func:`_cse_program`); every example model stays below the limit.
SYMPY_CSE_LIMIT = 500_000


def eliminate_common_subexpressions(spec: FunctionSpec, counts: dict[str, int] | None = None) -> OptimizedFunction:
    """Run one CSE over every entry of every output of ``spec`` (and over its definitions).

    The result is deterministic: sympy's canonical ordering is used (SymEngine's for programs and for
    functions over :data:`SYMPY_CSE_LIMIT`) and temporaries are
    numbered in CSE's evaluation order (``_x0``, ``_x1``...; :func:`symkin.optimize.demand_order` then
    reorders them, keeping the names).  The definitions of a spec become
    temporaries too (see :func:`_cse_program`).

    Args:
        spec: the function to optimize.
        counts: op counts of earlier stages, extended with ``cse`` (temporaries + outputs).
    """
    entries = [e for out in spec.outputs for e in out.entries]
    counts = dict(counts or {})
    if spec.definitions or spec_op_count(spec) > SYMPY_CSE_LIMIT:
        temporaries, reduced = _cse_program(spec.definitions, entries)
    else:
        with distribute(False):  # keep 2*(x + y) as one product (see passes.fold_parameters)
            temporaries, reduced = _merge_repeats(*sympy.cse(entries, symbols=sympy.numbered_symbols(
                TEMPORARY_PREFIX, real=True)))
    outputs = []
    start = 0
    for out in spec.outputs:
        size = len(out.entries)
        outputs.append(tuple(reduced[start:start + size]))
        start += size
    counts["cse"] = op_count([e for _, e in temporaries] + list(reduced))
    return OptimizedFunction(spec, tuple(temporaries), tuple(outputs), counts)


def _merge_repeats(temporaries: list[Assignment], reduced: list[sympy.Expr]) -> tuple[list[Assignment],
                                                                                     list[sympy.Expr]]:
    """sympy's CSE result with every repeated right-hand side an alias of its first occurrence.

    sympy's CSE can leave one product twice (``0.8660254037844386*_x127`` in the DELTA's
    closure Jacobians: its rewriting of negated products finds the two after it has named
    them).  Unchanged when nothing repeats; otherwise the temporaries are renumbered in order.
    """
    first: dict[sympy.Expr, sympy.Symbol] = {}
    alias: dict[sympy.Symbol, sympy.Symbol] = {}
    kept = []
    for symbol, expr in temporaries:
        expr = expr.xreplace(alias) if alias else expr
        if expr in first:
            alias[symbol] = first[expr]
        else:
            first[expr] = symbol
            kept.append((symbol, expr))
    if not alias:
        return temporaries, reduced
    names = sympy.numbered_symbols(TEMPORARY_PREFIX, real=True)
    rename = {symbol: next(names) for symbol, _ in kept}
    rename.update({symbol: rename[first_use] for symbol, first_use in alias.items()})
    return ([(rename[symbol], expr.xreplace(rename)) for symbol, expr in kept],
            [e.xreplace(rename) for e in reduced])


def _cse_program(definitions: tuple[Assignment, ...], entries: list[sympy.Expr]) -> tuple[list[Assignment],
                                                                                         list[sympy.Expr]]:
    """One CSE over the definitions and the output entries of a straight-line program.

    Programs (the dynamics) hold thousands of definitions, on which ``sympy.cse`` takes
    seconds; SymEngine's CSE (deterministic, independent of the hash seed) takes tens of
    milliseconds, so it runs here (see :mod:`symkin.symengine_bridge`).  Definition symbols
    are atoms to the CSE; the new temporaries and the (reduced) definitions are then put in
    a dependency order (depth first, in list order, so the result does not depend on set
    iteration order), definitions that reduced to a single symbol or number, or to the value of
    an earlier assignment, are substituted away, and everything is renamed ``_x0, _x1...`` in
    evaluation order.  Deep graphs are value-numbered before SymEngine's CSE
    (:func:`~symkin.expression_dag.name_shared_nodes_of_deep_graphs`).
    """
    exprs = [e for _, e in definitions] + entries
    symbols = {s.name: s for s in free_symbols(exprs)}
    symbols.update((s.name, s) for s, _ in definitions)
    memo: dict = {}
    named: list[tuple[se.Symbol, se.Basic]] = []

    def name(value: se.Basic) -> se.Symbol:
        named.append((se.Symbol(f"{VALUE_PREFIX}{len(named)}"), value))
        return named[-1][0]

    converted = name_shared_nodes_of_deep_graphs([to_symengine(e, memo) for e in exprs], name)
    # The named values go through the CSE too (sums shared between them are found there).
    found, reduced = se.cse([value for _, value in named] + converted)
    named, reduced = [(symbol, value) for (symbol, _), value in zip(named, reduced)], reduced[len(named):]
    assignments = named + list(found) + [(to_symengine(symbol, memo), expr)
                                         for (symbol, _), expr in zip(definitions, reduced)]
    # Final names in evaluation order.  Value numbering: an assignment that reduced to an atom,
    # or to the right-hand side of an earlier one (once the aliases before it are substituted),
    # is an alias, so no function evaluates the same right-hand side twice (the parts of a
    # combined function number their definitions apart: M, V and G each rebuild the link terms).
    names = sympy.numbered_symbols(TEMPORARY_PREFIX, real=True)
    kept = []
    alias: dict[se.Basic, se.Basic] = {}
    first_with_value: dict[se.Basic, se.Basic] = {}
    for symbol, expr in _dependency_order(assignments):
        used = {s: alias[s] for s in expr.free_symbols if s in alias}
        if used:
            expr = expr.xreplace(used)
        if expr.is_Atom:
            alias[symbol] = expr
        elif expr in first_with_value:
            alias[symbol] = first_with_value[expr]
        else:
            first_with_value[expr] = symbol
            kept.append((symbol, expr))
    outputs = [e.xreplace({s: alias[s] for s in e.free_symbols if s in alias}) for e in reduced[len(definitions):]]
    kept = used_by(kept, outputs)
    for symbol, _ in kept:
        symbols[symbol.name] = next(names)
    convert = SympyConverter(symbols)
    temporaries = [(symbols[symbol.name], convert(expr)) for symbol, expr in kept]
    return temporaries, [convert(e) for e in outputs]


def used_by(assignments: list[Assignment], outputs: list) -> list[Assignment]:
    """The ``assignments`` (in dependency order) that ``outputs`` need, directly or through others:
    a definition whose every use was rewritten away (trig of a sum expanded) is not emitted."""
    needed = {s for e in outputs for s in e.free_symbols}
    kept = []
    for symbol, expr in reversed(assignments):
        if symbol in needed:
            kept.append((symbol, expr))
            needed.update(expr.free_symbols)
    return kept[::-1]


def _dependency_order(assignments: list[Assignment]) -> list[Assignment]:
    """``assignments`` reordered so that each comes after those it uses (stable, iterative DFS)."""
    index = {symbol: k for k, (symbol, _) in enumerate(assignments)}
    operands = [sorted((index[s] for s in expr.free_symbols if s in index), reverse=True) for _, expr in assignments]
    order: dict[int, None] = {}                                 # insertion-ordered
    post_order(range(len(assignments)), order, lambda k: None, lambda k: operands[k])
    return [assignments[k] for k in order]

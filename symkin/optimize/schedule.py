"""The order of a function's temporaries: each computed just before the first output entry that needs it.

CSE gives the temporaries in an order of its own (sympy's discovery order, SymEngine's for programs): a
temporary is often computed long before its first use, and every value computed and not yet used for the last
time is live - in a register, or spilled to the stack and loaded back.  :func:`demand_order` orders them as the
outputs ask for them: the output entries are taken in order (outputs, then entries row-major) and each entry's
temporaries not yet computed are computed depth first, each after the ones it uses (a post-order walk of the
expression DAG from the entry, the operands in their CSE order).  An entry's temporaries then sit together, just
before it, and a backend that stores each entry as soon as its last temporary is computed
(:func:`store_positions`: the C and numpy backends; numpy also drops each temporary after its last use,
:func:`last_uses`) keeps few values live at a time - the classic locality order of
register allocation for straight-line code (Sethi and Ullman, "The Generation of Optimal Code for Arithmetic
Expressions", J. ACM 17, 1970, for trees; for a DAG a heuristic).

The reverse-mode derivative program of the UR10e's dynamics (``inverse_dynamics_derivatives``, every parameter
folded, 3 092 operations) needs its forward pass's values in the backward sweeps: 321 values live at the peak in
CSE's order, 211 in demand order with the stores interleaved.  GCC 12 (-O3 -march=native) then refers to the stack
1 734 times in the single call instead of 2 157 (spills and reloads; counted once in its ``gcc -S`` output), and the
call takes 536 ns instead of 583, the batch 164 ns per configuration instead of 180 (``benchmarks/bench_eval.py``,
C columns).  The order is a heuristic, kept where it holds fewer values live than CSE's
(:func:`peak_live`; the UR10e's forward-dynamics derivatives keep CSE's).  The arithmetic is the same operations on
the same operands in the same order, so every backend's results are bit for bit those of CSE's order.  So the
temporaries keep CSE's names, which no longer follow the evaluation order: renamed, the terms of a sum that sympy
sorts by name would be added in another order, and round otherwise.
"""

from __future__ import annotations

from typing import NamedTuple

from symkin.expression_dag import post_order
from symkin.ir.spec import OptimizedFunction


def demand_order(function: OptimizedFunction) -> OptimizedFunction:
    """``function`` with its temporaries in the order its output entries need them (see the module docstring),
    where that holds fewer values live at once (:func:`peak_live`) than CSE's order; else ``function`` as it is.
    Temporaries no entry needs (none after CSE) keep their relative order after the others."""
    temporaries = function.temporaries
    index = {symbol: k for k, (symbol, _) in enumerate(temporaries)}
    operands = [sorted((index[s] for s in expr.free_symbols if s in index), reverse=True) for _, expr in temporaries]
    computed: dict[int, None] = {}                              # insertion-ordered: the order of computation
    for entry in (e for output in function.outputs for e in output):
        # operands listed last are walked first (expression_dag.post_order): the lowest CSE number first
        post_order(sorted(index[s] for s in entry.free_symbols if s in index), computed, lambda k: None,
                   lambda k: operands[k])
    order = list(computed) + [k for k in range(len(temporaries)) if k not in computed]
    reordered = OptimizedFunction(function.spec, tuple(temporaries[k] for k in order), function.outputs,
                                  function.op_counts)
    return reordered if peak_live(reordered) < peak_live(function) else function


def store_positions(function: OptimizedFunction) -> list[list[int]]:
    """For each output entry, the number of temporaries computed before it can be stored: one past the last
    temporary it uses (0 for an entry of inputs and constants alone)."""
    index = {symbol: k for k, (symbol, _) in enumerate(function.temporaries)}
    return [[1 + max((index[s] for s in e.free_symbols if s in index), default=-1) for e in output]
            for output in function.outputs]


class Step(NamedTuple):
    """One statement of a straight-line program that stores its outputs early (:func:`steps`): ``kind`` is
    "temporary" (temporary ``number``), "store" (entry ``entry`` of output ``number``) or "dead" (the temporaries
    ``dead``, used for the last time by now)."""

    kind: str
    number: int = 0
    entry: int = 0
    dead: tuple[int, ...] = ()


def steps(function: OptimizedFunction) -> list[Step]:
    """The temporaries in order, each output entry stored right after the last temporary it uses
    (:func:`store_positions`; entries of inputs and constants alone first), and after each temporary with its
    stores the temporaries dead from there on (:func:`last_uses`): what every backend that stores early emits."""
    positions = store_positions(function)
    stores: list[list[Step]] = [[] for _ in range(len(function.temporaries) + 1)]
    for output, entries in enumerate(positions):
        for entry, position in enumerate(entries):
            stores[position].append(Step("store", output, entry))
    dead: list[list[int]] = [[] for _ in function.temporaries]
    for k, last in enumerate(last_uses(function, positions)):
        dead[last].append(k)
    program = list(stores[0])
    for k, (after, names) in enumerate(zip(stores[1:], dead)):
        program.append(Step("temporary", k))
        program.extend(after)
        if names:
            program.append(Step("dead", dead=tuple(names)))
    return program


def last_uses(function: OptimizedFunction, positions: list[list[int]] | None = None) -> list[int]:
    """For each temporary, the last temporary after which it is still needed: its last user among the temporaries,
    or the last temporary before the store of an output entry that uses it (``positions``, by default
    :func:`store_positions`); its own position where nothing uses it.  After that temporary (and the stores that
    follow it) it is dead."""
    index = {symbol: k for k, (symbol, _) in enumerate(function.temporaries)}
    last = list(range(len(function.temporaries)))
    for user, (_, expr) in enumerate(function.temporaries):
        for s in expr.free_symbols:
            if s in index:
                last[index[s]] = max(last[index[s]], user)
    for output, entries in zip(function.outputs, store_positions(function) if positions is None else positions):
        for entry, position in zip(output, entries):
            for s in entry.free_symbols:
                if s in index:
                    last[index[s]] = max(last[index[s]], position - 1)
    return last


def peak_live(function: OptimizedFunction) -> int:
    """The most temporaries live at once - computed and used again later - when each output entry is stored as
    soon as its last temporary is computed (:func:`store_positions`): the values a compiler must keep in registers
    or spill, the arrays a batched backend holds."""
    changes = [0] * (len(function.temporaries) + 1)
    for k, last in enumerate(last_uses(function)):
        changes[k] += 1
        changes[last] -= 1
    live = peak = 0
    for change in changes:
        live += change
        peak = max(peak, live)
    return peak

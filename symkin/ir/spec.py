"""Function specs: what one generated function computes, independent of any language.

A :class:`FunctionSpec` names a function, its ordered inputs (coordinate vectors such as
``q`` and ``qd``, then scalar parameters) and its outputs (sympy matrices with a declared
shape).  The optimizer turns it into an :class:`OptimizedFunction` (common subexpressions
pulled out into temporaries); every backend prints from that one representation, so the
numpy, C and CasADi code cannot drift apart.

A spec may also carry *definitions*: named intermediate values ``(symbol, expression)`` in
evaluation order, which later definitions and the outputs use like inputs.  Derivations
whose results are large shared graphs (the dynamics: M, C, solves on M) hand them over as
such a straight-line program, because writing them out as one sympy tree per entry would
repeat every shared subexpression at each use.  The optimizer treats definitions and
outputs together (folding, one CSE) and emits every definition as a temporary, so backends
see only :class:`OptimizedFunction` temporaries and never need to know.

A spec may also carry *column maps* (:class:`ColumnMap`): one small straight-line body applied
to r columns of values (the substitutions of a solve with given factors, one column per
right-hand side).  The optimized function holds them twice: unrolled into its temporaries, so
every backend and analysis that reads straight-line code works unchanged, and as a
:class:`MapBlock` naming those temporaries, which a backend with loops prints as one loop
over the columns (the C backend: the body's code once instead of r times, the instruction
cache's share of the derivatives of the dynamics, issue 65).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import sympy

from symkin.errors import DerivationError
from symkin.expression_dag import free_symbols
from symkin.model.schema import Model

#: Prefix of definition symbols (``_w0``, ``_w1``...); no model name starts with "_".
DEFINITION_PREFIX = "_w"
#: Prefixes of a column map's symbols: its results as the function sees them (``_y<map>_<column>_<k>``), and inside
#: its body the values shared by the columns (``_s<k>``), one column's values (``_b<k>``) and the body's
#: assignments (``_u<k>``).
MAP_TARGET_PREFIX = "_y"
MAP_SHARED_PREFIX = "_s"
MAP_COLUMN_PREFIX = "_b"
MAP_BODY_PREFIX = "_u"

#: The most that a notebook shows as LaTeX (``_repr_latex_``): equations, and operations over all of them
#: (sympy.count_ops); beyond either the formulas no longer fit a screen and Jupyter shows the text repr.
LATEX_MAX_EQUATIONS = 12
LATEX_MAX_OPS = 200


def latex_equations(equations: Sequence[tuple[sympy.Basic, sympy.Basic]]) -> str | None:
    r"""``name = expression`` lines (names as symbols) as one LaTeX display (what ``_repr_latex_``
    returns), or None beyond :data:`LATEX_MAX_EQUATIONS` equations or :data:`LATEX_MAX_OPS` operations.
    Definition symbols ``_w<k>`` print as w_k, output names upright (``\mathrm{base\_T\_tcp}``)."""
    if len(equations) > LATEX_MAX_EQUATIONS or sum(sympy.count_ops(e) for _, e in equations) > LATEX_MAX_OPS:
        return None
    names = {s: f"w_{{{str(s)[len(DEFINITION_PREFIX):]}}}" for name, expr in equations
             for s in ({name} | expr.free_symbols) if isinstance(s, sympy.Symbol)
             and str(s).startswith(DEFINITION_PREFIX)}
    names.update({name: r"\mathrm{" + str(name).replace("_", r"\_") + "}" for name, _ in equations if name not in names})
    rows = [sympy.latex(name, symbol_names=names) + " &= " + sympy.latex(expr, symbol_names=names)
            for name, expr in equations]
    return r"$\displaystyle \begin{aligned}" + r" \\ ".join(rows) + r"\end{aligned}$"


@dataclass(frozen=True)
class InputSpec:
    """One input of a generated function.

    Attributes:
        name: argument name (``q``, ``qd``... or the parameter name).
        kind: ``"vector"`` (coordinate group, shape (n,)) or ``"parameter"`` (scalar).
        symbols: the sympy symbols bound to the input's elements.
        element_names: a name per element (joint names; the parameter name).
        units: a unit per element.
        doc: one-line description.
        default: default value of a parameter (exact), None for vectors.
    """

    name: str
    kind: str
    symbols: tuple[sympy.Symbol, ...]
    element_names: tuple[str, ...]
    units: tuple[str, ...]
    doc: str
    default: sympy.Expr | None = None

    @property
    def shape(self) -> tuple[int, ...]:
        return () if self.kind == "parameter" else (len(self.symbols),)

    @property
    def default_value(self) -> float:
        """The default of a parameter input as a float (a vector input has none: ValueError)."""
        if self.default is None:
            raise ValueError(f"input '{self.name}' is a {self.kind}, it has no default value")
        return float(self.default)


@dataclass(frozen=True)
class OutputSpec:
    """One output: a sympy matrix and the array shape it is returned with.

    ``shape`` is (r, c) for matrices, (r,) for column vectors and () for scalars; ``expr``
    is always a sympy matrix with r*c (or r, or 1) entries in row-major order.  ``elements``
    names the entries along the last axis where they are more than numbers in a row (the
    regressor's columns and parameters: ``link1.m``...); empty otherwise.
    """

    name: str
    expr: sympy.ImmutableMatrix
    doc: str
    unit: str = ""
    shape: tuple[int, ...] = field(default=())
    elements: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.shape:
            object.__setattr__(self, "shape", tuple(self.expr.shape) if self.expr.shape != (1, 1) else ())
        size = 1
        for s in self.shape:
            size *= s
        if size != len(self.expr):
            raise ValueError(f"output {self.name}: shape {self.shape} does not fit a {self.expr.shape} matrix")
        if self.elements and len(self.elements) != self.shape[-1]:
            raise ValueError(f"output {self.name}: {len(self.elements)} element names for a last axis of "
                             f"{self.shape[-1]}")

    @property
    def entries(self) -> list[sympy.Expr]:
        """The entries in row-major order."""
        return list(self.expr)

    def _repr_latex_(self) -> str | None:
        """The output as an equation in a notebook, where it is small (:data:`LATEX_MAX_OPS`)."""
        return latex_equations([(sympy.Symbol(self.name), self.expr if self.shape else self.expr[0])])


@dataclass(frozen=True)
class ColumnMap:
    """One straight-line body evaluated for r columns of values: a loop where the backend has loops.

    Attributes:
        shared: (body symbol ``_s<k>``, value) of the values every column reads (a solve's factors); the values
            are expressions of the function's inputs and definitions.
        parameters: the body's symbols ``_b<k>`` of one column's values.
        body: the body's assignments ``(_u<k>, expression)`` in evaluation order, over the shared symbols, the
            parameters and earlier assignments.
        results: one column's results, expressions of the body's symbols.
        columns: r tuples of values for the parameters (expressions of the inputs and definitions).
        targets: r tuples of symbols ``_y..`` (one per result) by which the outputs use column c's results.
    """

    shared: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    parameters: tuple[sympy.Symbol, ...]
    body: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    results: tuple[sympy.Expr, ...]
    columns: tuple[tuple[sympy.Expr, ...], ...]
    targets: tuple[tuple[sympy.Symbol, ...], ...]

    def __post_init__(self) -> None:
        if len(self.columns) != len(self.targets):
            raise ValueError(f"{len(self.columns)} columns for {len(self.targets)} tuples of targets")
        if any(len(c) != len(self.parameters) for c in self.columns) or any(
                len(t) != len(self.results) for t in self.targets):
            raise ValueError("a column map's columns must each give every parameter and take every result")

    def rewritten(self, rewrite: Callable[[sympy.Expr], sympy.Expr]) -> ColumnMap:
        """The map with ``rewrite`` applied to its shared values and its columns (the function's expressions)."""
        return dataclasses.replace(self, shared=tuple((s, rewrite(v)) for s, v in self.shared),
                                   columns=tuple(tuple(rewrite(v) for v in c) for c in self.columns))

    def values(self) -> list[sympy.Expr]:
        """Its shared values, then its columns' values parameter by parameter (``columns[c][k]`` for every c, k
        after k), flat: what the function computes for it, in the order of the array ``[k][c]`` (a solve's
        right-hand sides row by row; the rows of a derivative come from one adjoint sweep each)."""
        return [v for _, v in self.shared] + [c[k] for k in range(len(self.parameters)) for c in self.columns]


def map_targets(number: int, columns: int, results: int) -> tuple[tuple[sympy.Symbol, ...], ...]:
    """The target symbols ``_y<number>_<column>_<k>`` of a function's column map ``number``."""
    return tuple(tuple(sympy.Symbol(f"{MAP_TARGET_PREFIX}{number}_{c}_{k}", real=True) for k in range(results))
                 for c in range(columns))


@dataclass(frozen=True)
class FunctionSpec:
    """A function to generate.

    Attributes:
        name: function name in every backend.
        summary: one-line summary.
        doc: longer description with the equation or reference implemented.
        inputs: ordered inputs: vectors first, then parameters in model order.
        outputs: ordered outputs.
        definitions: named intermediate values ``(symbol, expression)``, in evaluation
            order; an expression may use the inputs and earlier definitions, the outputs
            may use all of them (see the module docstring).  Definition symbols are named
            ``_w<k>`` (:data:`DEFINITION_PREFIX`), which no model name can be.
        parts: for a combined function (see :func:`combine_functions`), the names of the
            functions whose outputs it computes together; empty otherwise.
        maps: column maps (:class:`ColumnMap`) evaluated after the definitions; the outputs use
            their targets.
    """

    name: str
    summary: str
    doc: str
    inputs: tuple[InputSpec, ...]
    outputs: tuple[OutputSpec, ...]
    definitions: tuple[tuple[sympy.Symbol, sympy.Expr], ...] = ()
    parts: tuple[str, ...] = ()
    maps: tuple[ColumnMap, ...] = ()

    @property
    def vector_inputs(self) -> tuple[InputSpec, ...]:
        return tuple(i for i in self.inputs if i.kind != "parameter")

    def _repr_latex_(self) -> str | None:
        """Its definitions and outputs as equations in a notebook, where they are small (:data:`LATEX_MAX_OPS`)."""
        return latex_equations([*self.definitions, *((sympy.Symbol(o.name), o.expr if o.shape else o.expr[0])
                                                     for o in self.outputs)])

    @property
    def parameter_inputs(self) -> tuple[InputSpec, ...]:
        return tuple(i for i in self.inputs if i.kind == "parameter")

    def straight_line_definitions(self) -> tuple[tuple[sympy.Symbol, sympy.Expr], ...]:
        """The definitions, then every column map unrolled into more: per column its body's assignments (named
        ``_y<map>_<column><body symbol>``) and its targets, each the value of a result (what an evaluator of
        straight-line code reads)."""
        definitions = list(self.definitions)
        for number, column_map in enumerate(self.maps):
            for c, (column, targets) in enumerate(zip(column_map.columns, column_map.targets)):
                local = dict(column_map.shared) | dict(zip(column_map.parameters, column))
                for symbol, expr in column_map.body:
                    named = sympy.Symbol(f"{MAP_TARGET_PREFIX}{number}_{c}{symbol.name}", real=True)
                    definitions.append((named, expr.xreplace(local)))
                    local[symbol] = named
                definitions += [(t, r.xreplace(local)) for t, r in zip(targets, column_map.results)]
        return tuple(definitions)

    def expanded_outputs(self) -> tuple[sympy.ImmutableMatrix, ...]:
        """The output matrices with every definition substituted (plain expressions of the inputs).

        Meant for small specs and tests (symbolic comparisons): for a large program the
        expanded trees can be far bigger than the program itself.
        """
        if not self.definitions and not self.maps:
            return tuple(o.expr for o in self.outputs)
        values: dict[sympy.Symbol, sympy.Expr] = {}
        for symbol, expr in self.straight_line_definitions():
            values[symbol] = expr.xreplace(values)
        return tuple(sympy.ImmutableMatrix(o.expr.xreplace(values)) for o in self.outputs)


@dataclass(frozen=True)
class MapBlock:
    """A column map (:class:`ColumnMap`) of an optimized function: its columns unrolled into the function's
    temporaries ``start`` to ``stop`` (exclusive), which no other temporary lies between, and the body that
    computes any one of them, for the backends that print it once, as a loop over the columns.

    Attributes:
        start, stop: the unrolled temporaries' range.
        parameters: the body's symbols of one column's values.
        body: its assignments over the parameters and the function's temporaries and inputs (the shared values).
        results: one column's results over the body's symbols.
        columns: per column, the values of the parameters: symbols of the function or numbers.
        targets: per column, its results as the unrolled code holds them (temporaries of the block, or atoms
            where a result folded to a number or a value computed before the block).
    """

    start: int
    stop: int
    parameters: tuple[sympy.Symbol, ...]
    body: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    results: tuple[sympy.Expr, ...]
    columns: tuple[tuple[sympy.Expr, ...], ...]
    targets: tuple[tuple[sympy.Expr, ...], ...]


@dataclass(frozen=True)
class OptimizedFunction:
    """A function spec after the optimization passes.

    Attributes:
        spec: the spec after folding (fixed parameters removed from the inputs).
        temporaries: (symbol, expression) assignments, in evaluation order.
        outputs: per output, its entries (row-major) written in terms of inputs and temporaries.
        op_counts: operation counts by stage, e.g. {"derived": 410, "folded": 380, "cse": 120}.
        maps: the spec's column maps, each unrolled into a run of the temporaries (:class:`MapBlock`).
    """

    spec: FunctionSpec
    temporaries: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    outputs: tuple[tuple[sympy.Expr, ...], ...]
    op_counts: dict[str, int]
    maps: tuple[MapBlock, ...] = ()

    @property
    def name(self) -> str:
        return self.spec.name


def make_function(model: Model, name: str, summary: str, doc: str,
                  vectors: Sequence[InputSpec], outputs: Sequence[OutputSpec],
                  definitions: Sequence[tuple[sympy.Symbol, sympy.Expr]] = (),
                  maps: Sequence[ColumnMap] = ()) -> FunctionSpec:
    """Build a spec whose parameter inputs are the model parameters its outputs use.

    Raises:
        DerivationError: if an output uses a symbol that no input provides.
    """
    used = free_symbols([e for out in outputs for e in out.expr] + [expr for _, expr in definitions]
                        + [v for m in maps for v in m.values()])
    used -= {symbol for symbol, _ in definitions} | {t for m in maps for column in m.targets for t in column}
    params = tuple(
        InputSpec(p.name, "parameter", (p.symbol,), (p.name,), (p.unit,), p.doc, p.value)
        for p in model.parameters if p.symbol in used
    )
    provided = {s for i in tuple(vectors) + params for s in i.symbols}
    missing = used - provided
    if missing:
        raise DerivationError(f"{name}: outputs use {sorted(map(str, missing))} which no input provides")
    return FunctionSpec(name, summary, doc, tuple(vectors) + params, tuple(outputs), tuple(definitions),
                        maps=tuple(maps))


def combine_functions(model: Model, name: str, specs: Sequence[FunctionSpec]) -> FunctionSpec:
    """One function computing the outputs of all ``specs`` together (e.g. M, V and G).

    Optimizing the combined spec runs one CSE across every output, so work shared between
    the quantities (sines and cosines of q, link transforms) is done once per call.

    The vector inputs are those of the parts in order of first use; the parameters are the
    model parameters any output uses, in model order (as :func:`make_function`).  An output
    keeps its name when no other part has an output of the same name and no input has it,
    and is called ``<part>_<output>`` otherwise (``jacobian_J`` and ``jacobian_geometric_J``;
    ``forward_dynamics_qdd`` next to the input ``qdd`` of inverse dynamics).

    Raises:
        DerivationError: two parts give different symbols to a vector input of one name.
    """
    vectors: dict[str, InputSpec] = {}
    for spec in specs:
        for v in spec.vector_inputs:
            known = vectors.setdefault(v.name, v)
            if known.symbols != v.symbols:
                raise DerivationError(f"{name}: the parts disagree on the input '{v.name}'")
    counts: dict[str, int] = {name: 1 for name in vectors}  # an output may not take an input's name
    for spec in specs:
        for out in spec.outputs:
            counts[out.name] = counts.get(out.name, 0) + 1
    # Each part numbers its definitions from _w0: renumber them so the parts cannot clash
    # (identical work in several parts is then shared by the one CSE over the combination).
    definitions: list[tuple[sympy.Symbol, sympy.Expr]] = []
    maps: list[ColumnMap] = []
    outputs = []
    for spec in specs:
        renamed: dict[sympy.Symbol, sympy.Symbol] = {}
        for symbol, expr in spec.definitions:
            renamed[symbol] = sympy.Symbol(f"{DEFINITION_PREFIX}{len(definitions)}", **symbol.assumptions0)
            definitions.append((renamed[symbol], expr.xreplace(renamed)))
        for column_map in spec.maps:  # the maps are numbered apart too
            targets = map_targets(len(maps), len(column_map.targets), len(column_map.results))
            renamed.update(zip((t for c in column_map.targets for t in c), (t for c in targets for t in c)))
            maps.append(dataclasses.replace(column_map.rewritten(lambda e: e.xreplace(renamed)), targets=targets))
        outputs += [OutputSpec(out.name if counts[out.name] == 1 else f"{spec.name}_{out.name}",
                               sympy.ImmutableMatrix(out.expr.xreplace(renamed)), f"{out.doc} ({spec.name})",
                               out.unit, out.shape, out.elements)
                    for out in spec.outputs]
    parts = tuple(spec.name for spec in specs)
    summary = f"{', '.join(parts)} together, with one set of shared subexpressions."
    doc = ("Computes the outputs of " + ", ".join(parts) + " in one call; subexpressions common to "
           "several of them are evaluated once.")
    combined = make_function(model, name, summary, doc, list(vectors.values()), outputs, definitions, maps)
    return dataclasses.replace(combined, parts=parts)

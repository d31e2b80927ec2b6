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
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import sympy

from symkin.errors import DerivationError
from symkin.expression_dag import free_symbols
from symkin.model.schema import Model

#: Prefix of definition symbols (``_w0``, ``_w1``...); no model name starts with "_".
DEFINITION_PREFIX = "_w"

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
    """

    name: str
    summary: str
    doc: str
    inputs: tuple[InputSpec, ...]
    outputs: tuple[OutputSpec, ...]
    definitions: tuple[tuple[sympy.Symbol, sympy.Expr], ...] = ()
    parts: tuple[str, ...] = ()

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

    def expanded_outputs(self) -> tuple[sympy.ImmutableMatrix, ...]:
        """The output matrices with every definition substituted (plain expressions of the inputs).

        Meant for small specs and tests (symbolic comparisons): for a large program the
        expanded trees can be far bigger than the program itself.
        """
        if not self.definitions:
            return tuple(o.expr for o in self.outputs)
        values: dict[sympy.Symbol, sympy.Expr] = {}
        for symbol, expr in self.definitions:
            values[symbol] = expr.xreplace(values)
        return tuple(sympy.ImmutableMatrix(o.expr.xreplace(values)) for o in self.outputs)


@dataclass(frozen=True)
class OptimizedFunction:
    """A function spec after the optimization passes.

    Attributes:
        spec: the spec after folding (fixed parameters removed from the inputs).
        temporaries: (symbol, expression) assignments, in evaluation order.
        outputs: per output, its entries (row-major) written in terms of inputs and temporaries.
        op_counts: operation counts by stage, e.g. {"derived": 410, "folded": 380, "cse": 120}.
    """

    spec: FunctionSpec
    temporaries: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    outputs: tuple[tuple[sympy.Expr, ...], ...]
    op_counts: dict[str, int]

    @property
    def name(self) -> str:
        return self.spec.name


def make_function(model: Model, name: str, summary: str, doc: str,
                  vectors: Sequence[InputSpec], outputs: Sequence[OutputSpec],
                  definitions: Sequence[tuple[sympy.Symbol, sympy.Expr]] = ()) -> FunctionSpec:
    """Build a spec whose parameter inputs are the model parameters its outputs use.

    Raises:
        DerivationError: if an output uses a symbol that no input provides.
    """
    used = free_symbols([e for out in outputs for e in out.expr] + [expr for _, expr in definitions])
    used -= {symbol for symbol, _ in definitions}
    params = tuple(
        InputSpec(p.name, "parameter", (p.symbol,), (p.name,), (p.unit,), p.doc, p.value)
        for p in model.parameters if p.symbol in used
    )
    provided = {s for i in tuple(vectors) + params for s in i.symbols}
    missing = used - provided
    if missing:
        raise DerivationError(f"{name}: outputs use {sorted(map(str, missing))} which no input provides")
    return FunctionSpec(name, summary, doc, tuple(vectors) + params, tuple(outputs), tuple(definitions))


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
    outputs = []
    for spec in specs:
        renamed: dict[sympy.Symbol, sympy.Symbol] = {}
        for symbol, expr in spec.definitions:
            renamed[symbol] = sympy.Symbol(f"{DEFINITION_PREFIX}{len(definitions)}", **symbol.assumptions0)
            definitions.append((renamed[symbol], expr.xreplace(renamed)))
        outputs += [OutputSpec(out.name if counts[out.name] == 1 else f"{spec.name}_{out.name}",
                               sympy.ImmutableMatrix(out.expr.xreplace(renamed)), f"{out.doc} ({spec.name})",
                               out.unit, out.shape, out.elements)
                    for out in spec.outputs]
    parts = tuple(spec.name for spec in specs)
    summary = f"{', '.join(parts)} together, with one set of shared subexpressions."
    doc = ("Computes the outputs of " + ", ".join(parts) + " in one call; subexpressions common to "
           "several of them are evaluated once.")
    combined = make_function(model, name, summary, doc, list(vectors.values()), outputs, definitions)
    return dataclasses.replace(combined, parts=parts)

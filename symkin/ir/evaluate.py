"""Direct evaluation of a FunctionSpec as derived: the reference every backend is compared with.

The un-optimized outputs (and the spec's definitions program, evaluated in order as
assignments) are lambdified for numpy or mpmath; nothing of the optimizer or the printers
is involved, so the result is an independent check of generated code.  For numeric work
inside symkin on a derived function (the platform-motion check), :func:`symengine_entries`
builds the same values through SymEngine in a fraction of lambdify's time.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np
import symengine as se
import sympy

from symkin.symengine_bridge import to_symengine
from symkin.ir.opcount import spec_op_count
from symkin.ir.spec import FunctionSpec

#: Above this many operations (a Laplace-expanded 6x6 determinant, the Stewart-Gough closure
#: Jacobians) outputs are evaluated through sympy's own CSE: printing and evaluating them as one
#: flat expression takes minutes, and sharing subexpressions only changes how the same
#: expression is evaluated.
SHARED_EVALUATION_OPS = 20000
#: SymEngine's compiler for :func:`symengine_entries`: LLVM (doubles) where SymEngine was built
#: with it, as its PyPI wheels are; else its tree-walking interpreter.
SYMENGINE_BACKEND = "llvm" if se.have_llvm else "lambda"


def lambdify_spec(spec: FunctionSpec, args: Sequence[object], modules: str | Sequence[object] = "numpy",
                  values: Mapping[sympy.Symbol, sympy.Expr] | None = None, printer: object = None
                  ) -> Callable[..., list]:
    """A function of ``args`` returning every output entry of ``spec`` (row-major, outputs in order).

    Args:
        spec: the derived function (its definitions become assignments before the outputs).
        args: lambdify arguments: symbols, or sequences of symbols for vector arguments.
        modules: ``"numpy"`` or ``"mpmath"``, or a list of namespaces before one of them (as lambdify's).
        values: substitutions applied first (e.g. parameters at their defaults).
        printer: lambdify's code printer (default: :func:`reference_printer` of ``modules``).
    """
    values = dict(values or {})
    definitions = [(s, e.xreplace(values)) for s, e in spec.straight_line_definitions()]
    entries = [e.xreplace(values) for out in spec.outputs for e in out.entries]
    share = spec_op_count(spec) > SHARED_EVALUATION_OPS

    def program(exprs: list[sympy.Expr]) -> tuple[list, list]:
        if not share:
            return definitions, exprs
        shared, reduced = sympy.cse(exprs, symbols=sympy.numbered_symbols("_ref"), order="none")
        return definitions + shared, reduced

    # use_imps=False: no implemented functions occur, and looking for them walks every node of the
    # expanded trees (three quarters of the lambdify time of the Stewart platform's dynamics)
    return sympy.lambdify(list(args), entries, modules=modules, cse=program, use_imps=False,
                          printer=printer if printer is not None else reference_printer(modules))


#: lambdify's settings of its printers (sympy.utilities.lambdify), terms printed in their stored order: sorting the
#: terms of every sum (sympy's default ``order``) took half of the printing of the Stewart platform's references, and
#: the order of a sum's terms changes only its rounding, which every comparison with a reference allows for.
REFERENCE_PRINTER_SETTINGS = {"fully_qualified_modules": False, "inline": True, "allow_unknown_functions": True,
                              "order": "none"}


def reference_printer(modules: str | Sequence[object]) -> object:
    """The code printer lambdify would choose for ``modules`` (mpmath's where mpmath is among them, else numpy's),
    with :data:`REFERENCE_PRINTER_SETTINGS` and the names of ``modules``' namespaces as user functions."""
    from sympy.printing.numpy import NumPyPrinter
    from sympy.printing.pycode import MpmathPrinter

    listed = [modules] if isinstance(modules, str) else list(modules)
    printer = MpmathPrinter if "mpmath" in listed else NumPyPrinter
    user_functions = {name: name for namespace in listed if isinstance(namespace, Mapping) for name in namespace}
    return printer(dict(REFERENCE_PRINTER_SETTINGS, user_functions=user_functions))


def symengine_entries(spec: FunctionSpec, args: Sequence[sympy.Symbol],
                      values: Mapping[sympy.Symbol, sympy.Expr] | None = None,
                      backend: str = SYMENGINE_BACKEND) -> Callable[[np.ndarray], np.ndarray]:
    """f(X): every output entry of ``spec`` (row-major, outputs in order), (..., entries), at the rows X (...,
    len(args)) of argument values, through SymEngine's Lambdify with common subexpressions (its definitions
    substituted in order, ``values`` first).  Built in a fraction of :func:`lambdify_spec`'s time (the Stewart
    platform's closure: 0.2 s against 12 s); lambdify_spec stays the backends' reference.  Compiled by SymEngine's
    LLVM backend where its build has one (``backend``, default :data:`SYMENGINE_BACKEND`): a batch of the Stewart
    platform's closure rows about 30 times faster than its tree-walking ``lambda`` backend, which Newton's
    iterations call thousands of times (benchmarks/bench_closure_assembly.py)."""
    values = dict(values or {})
    memo: dict[sympy.Basic, se.Basic] = {}
    definitions: dict[se.Basic, se.Basic] = {}
    for symbol, expr in spec.straight_line_definitions():
        definitions[to_symengine(symbol)] = to_symengine(expr.xreplace(values), memo).subs(definitions)
    entries = [to_symengine(e.xreplace(values), memo).subs(definitions) for out in spec.outputs for e in out.entries]
    function = se.Lambdify([to_symengine(a) for a in args], entries, backend=backend, cse=True)
    return lambda X: np.asarray(function(np.asarray(X, dtype=float)), dtype=float)

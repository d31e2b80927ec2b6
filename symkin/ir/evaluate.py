"""Direct evaluation of a FunctionSpec as derived: the reference every backend is compared with.

The un-optimized outputs (and the spec's definitions program, evaluated in order as
assignments) are lambdified for numpy or mpmath; nothing of the optimizer or the printers
is involved, so the result is an independent check of generated code.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import sympy

from symkin.ir.opcount import spec_op_count
from symkin.ir.spec import FunctionSpec

#: Above this many operations (a Laplace-expanded 6x6 determinant, the Stewart-Gough closure
#: Jacobians) outputs are evaluated through sympy's own CSE: printing and evaluating them as one
#: flat expression takes minutes, and sharing subexpressions only changes how the same
#: expression is evaluated.
SHARED_EVALUATION_OPS = 20000


def lambdify_spec(spec: FunctionSpec, args: Sequence[object], modules: str | Sequence[object] = "numpy",
                  values: Mapping[sympy.Symbol, sympy.Expr] | None = None, printer: object = None
                  ) -> Callable[..., list]:
    """A function of ``args`` returning every output entry of ``spec`` (row-major, outputs in order).

    Args:
        spec: the derived function (its definitions become assignments before the outputs).
        args: lambdify arguments: symbols, or sequences of symbols for vector arguments.
        modules: ``"numpy"`` or ``"mpmath"``, or a list of namespaces before one of them (as lambdify's).
        values: substitutions applied first (e.g. parameters at their defaults).
        printer: lambdify's code printer (default: the one of ``modules``).
    """
    values = dict(values or {})
    definitions = [(s, e.xreplace(values)) for s, e in spec.definitions]
    entries = [e.xreplace(values) for out in spec.outputs for e in out.entries]
    share = spec_op_count(spec) > SHARED_EVALUATION_OPS

    def program(exprs: list[sympy.Expr]) -> tuple[list, list]:
        if not share:
            return definitions, exprs
        shared, reduced = sympy.cse(exprs, symbols=sympy.numbered_symbols("_ref"), order="none")
        return definitions + shared, reduced

    # use_imps=False: no implemented functions occur, and looking for them walks every node of the
    # expanded trees (three quarters of the lambdify time of the Stewart platform's dynamics)
    return sympy.lambdify(list(args), entries, modules=modules, cse=program, use_imps=False, printer=printer)

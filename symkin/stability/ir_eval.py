"""Evaluate an optimized function in a chosen floating-point type, through the numpy printer.

The generated numpy modules compute in float64 (their inputs are converted to float64).  To
measure what single precision does to the *same code*, the optimized IR (temporaries and
output entries after folding and CSE) is printed by the numpy backend's printer
(:class:`~symkin.backends.numpy.printer.BatchNumPyPrinter`) into a function whose inputs
and outputs are arrays of ``dtype``; with numpy's promotion rules (NEP 50) the printed
literals stay weak, so every operation runs in ``dtype``.  In float64 the result is
bit-identical to the generated module (checked by the tests), so float32 numbers describe
the generated code evaluated in single precision.  When the C backend gains a float
variant, its numbers can be compared with these.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from symkin.backends.numpy.printer import BatchNumPyPrinter
from symkin.ir.spec import OptimizedFunction


def compile_ir(function: OptimizedFunction, dtype: type = np.float32) -> Callable[..., np.ndarray]:
    """A callable ``f(vectors, parameters) -> (batch..., size)`` evaluating ``function`` in ``dtype``.

    Args:
        function: the optimized function.
        dtype: numpy floating type of every input, temporary and output.

    Returns:
        f taking {vector name: (..., n) array} and {parameter name: scalar or array} and
        returning every output entry, row-major, outputs in order, in the last axis.
    """
    printer = BatchNumPyPrinter()
    spec = function.spec
    lines = ["def evaluate(vectors, parameters):"]
    for v in spec.vector_inputs:
        lines.append(f"    {v.name} = numpy.asarray(vectors[{v.name!r}], dtype=dtype)")
        lines += [f"    {s} = {v.name}[..., {k}]" for k, s in enumerate(v.symbols)]
    for p in spec.parameter_inputs:
        lines.append(f"    {p.symbols[0]} = numpy.asarray(parameters[{p.name!r}], dtype=dtype)")
    shapes = [f"numpy.shape({v.name})[:-1]" for v in spec.vector_inputs] + \
             [f"numpy.shape({p.symbols[0]})" for p in spec.parameter_inputs]
    lines.append(f"    batch = numpy.broadcast_shapes({', '.join(shapes)})")
    lines += [f"    {s} = {printer.doprint(e)}" for s, e in function.temporaries]
    entries = [e for out in function.outputs for e in out]
    lines.append(f"    out = numpy.zeros(batch + ({len(entries)},), dtype=dtype)")
    lines += [f"    out[..., {k}] = {printer.doprint(e)}" for k, e in enumerate(entries) if e != 0]
    lines.append("    return out")
    namespace: dict = {"numpy": np, "dtype": dtype}
    exec(compile("\n".join(lines), f"<symkin ir {spec.name} {np.dtype(dtype).name}>", "exec"), namespace)  # noqa: S102
    return namespace["evaluate"]


def flatten_outputs(result: object, shapes: list[tuple[int, ...]]) -> np.ndarray:
    """The outputs of a generated function (an array or a named tuple of arrays, with the
    declared ``shapes``) as one array (batch..., size), row-major, outputs in order."""
    outputs = result if isinstance(result, tuple) else (result,)
    parts = []
    for out, shape in zip(outputs, shapes):
        out = np.asarray(out)
        parts.append(out.reshape(out.shape[:out.ndim - len(shape)] + (-1,)))
    return np.concatenate(parts, axis=-1)

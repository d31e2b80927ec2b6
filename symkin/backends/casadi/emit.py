"""Named ``casadi.Function`` objects from the optimized functions, serialized to ``.casadi`` files.

Every optimized function becomes ``casadi.Function(name, inputs, outputs, input_names,
output_names)`` with inputs ``q`` (n x 1), ``qd``... and one scalar input per free
parameter (so optimizers can vary them), and dense outputs shaped as declared (r x c,
r x 1 or 1 x 1; identically zero entries are stored zeros, as in the other backends).
Called by name (``f(q=q)``), an omitted parameter takes its model default and an omitted
vector input is NaN, so a forgotten ``q`` shows up instead of silently reading zeros.  The SX graph is built once from the IR: inputs, then the CSE temporaries in
order, then the outputs (:mod:`symkin.backends.casadi.sx`).

Determinism: CasADi's binary serialization of an SX function writes its algorithm (the
instruction list in the order the graph was built), its constants and names, and no
addresses or counters; since the graph is always built in the IR's order, the bytes
depend only on the IR and the CasADi version (pinned in requirements/constraints.txt).
The golden test regenerates the files in fresh processes with different hash seeds.
"""

from __future__ import annotations

import os
import tempfile

import casadi

from symkin.backends.casadi.sx import SXBuilder
from symkin.backends.naming import casadi_file, matrix_shape
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import OptimizedFunction


def build_function(f: OptimizedFunction) -> casadi.Function:
    """The named CasADi function of one optimized function."""
    spec = f.spec
    inputs = []
    symbols = {}
    for i in spec.inputs:
        if i.kind == "parameter":
            sx = casadi.SX.sym(i.name)
            symbols[i.symbols[0]] = sx
        else:
            sx = casadi.SX.sym(i.name, len(i.symbols))
            for k, s in enumerate(i.symbols):
                symbols[s] = sx[k]
        inputs.append(sx)
    builder = SXBuilder(symbols)
    for symbol, expr in f.temporaries:
        builder.bind(symbol, builder.doprint(expr))
    outputs = []
    for out, entries in zip(spec.outputs, f.outputs):
        rows, cols = matrix_shape(out.shape)
        matrix = casadi.SX.zeros(rows, cols)  # dense: zeros are values, as in the other backends
        for k, e in enumerate(entries):
            if e != 0:
                matrix[k // cols, k % cols] = builder.doprint(e)
        outputs.append(matrix)
    defaults = [i.default_value if i.kind == "parameter" else float("nan") for i in spec.inputs]
    return casadi.Function(spec.name, inputs, outputs, [i.name for i in spec.inputs], [o.name for o in spec.outputs],
                           {"default_in": defaults})


def serialize(function: casadi.Function) -> bytes:
    """The bytes ``function.save`` writes (CasADi saves only to files)."""
    fd, path = tempfile.mkstemp(suffix=".casadi")
    os.close(fd)
    try:
        function.save(path)
        with open(path, "rb") as handle:
            return handle.read()
    finally:
        os.unlink(path)


def emit_functions(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>_<function>.casadi: serialized function} for every function of ``code``."""
    return {casadi_file(code.name, f.name): serialize(build_function(f)) for f in code.functions}

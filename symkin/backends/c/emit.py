"""Printing of the C header and source from the optimized functions (templates/c/).

Calling convention (documented in the generated header):

* ``<model>_<function>(const double *q, ..., double p1, ..., double *out1, ...)``: vector
  inputs as pointers to their n elements, free parameters as scalars (model order), each
  output into a caller-owned array of its size, row-major (element (i, j) of an r x c
  matrix at ``out[i*c + j]``); every element is written;
* ``<model>_<function>_batch(size_t n, const double *q, ..., const double *params,
  size_t params_stride, double *out1, ...)``: n configurations stored one after the other
  (q is n x dof, out1 is n x size), the parameters packed in one array read at
  ``params + i*params_stride`` (stride 0: the same values for every configuration);
* with the float32 option, ``..._f32`` variants of both take and return ``float``.
"""

from __future__ import annotations

import textwrap
from typing import Any

from symkin.backends.c.printer import C_TYPES, CPrinter
from symkin.backends.naming import c_symbol
from symkin.backends.templating import provenance, render
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import OptimizedFunction

HEADER_TEMPLATE = "c/header.h.j2"
SOURCE_TEMPLATE = "c/source.c.j2"
DOC_WIDTH = 86

#: (precision, function-name suffix) of each emitted variant.
VARIANTS = {"double": "", "float": "_f32"}


def _comment_lines(text: str, width: int = DOC_WIDTH) -> list[str]:
    return textwrap.wrap(text.replace("*/", "* /"), width) or [""]


def _size(shape: tuple[int, ...]) -> int:
    size = 1
    for s in shape:
        size *= s
    return size


def _function_context(code: ModelCode, f: OptimizedFunction, precision: str, printer: CPrinter) -> dict[str, Any]:
    spec = f.spec
    ctype = C_TYPES[precision]
    suffix = VARIANTS[precision]
    used = set()
    for _, e in f.temporaries:
        used |= e.free_symbols
    for entries in f.outputs:
        for e in entries:
            used |= e.free_symbols
    vectors = []
    for v in spec.vector_inputs:
        vectors.append({
            "name": v.name, "size": len(v.symbols),
            "elements": [{"local": str(s), "index": k} for k, s in enumerate(v.symbols) if s in used],
            "doc": _comment_lines(f"{v.name}[{len(v.symbols)}]: {v.doc}: "
                                  + ", ".join(f"{n} [{u}]" for n, u in zip(v.element_names, v.units)) + "."),
        })
    params = []
    for p in spec.parameter_inputs:
        unit = f" [{p.units[0]}]" if p.units[0] else ""
        params.append({"name": p.name, "doc": _comment_lines(
            f"{p.name}: {p.doc or 'parameter'}{unit}; default {code.name.upper()}_DEFAULT_{p.name} "
            f"= {float(p.default)!r}.")})
    outputs = []
    for out, entries in zip(spec.outputs, f.outputs):
        size = _size(out.shape)
        shape = " x ".join(map(str, out.shape)) or "scalar"
        order = ", row-major" if len(out.shape) == 2 else ""
        outputs.append({
            "name": out.name, "size": size,
            "assignments": [{"index": k, "code": printer.doprint(e)} for k, e in enumerate(entries)],
            "doc": _comment_lines(f"{out.name}[{size}]: {shape}{order}; {out.doc}"
                                  + (f" [{out.unit}]" if out.unit else "") + "."),
        })
    return {
        "name": spec.name,
        "symbol": c_symbol(code.name, spec.name, suffix),
        "batch_symbol": c_symbol(code.name, spec.name, "_batch" + suffix),
        "kernel": c_symbol(code.name, spec.name, "_kernel" + suffix),
        "real": ctype,
        "summary": _comment_lines(spec.summary),
        "doc": _comment_lines(spec.doc),
        "vectors": vectors,
        "params": params,
        "outputs": outputs,
        "temporaries": [{"name": str(s), "code": printer.doprint(e)} for s, e in f.temporaries],
        "op_count": f.op_counts["cse"],
    }


def emit_sources(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>.h: header, <model>.c: source} for ``code``."""
    precisions = ["double", "float"] if code.float32 else ["double"]
    functions = [_function_context(code, f, precision, CPrinter(precision))
                 for precision in precisions for f in code.functions]
    model = {
        "name": code.name, "macro": code.name.upper(), "hash": code.hash,
        "description": _comment_lines(code.description or code.name),
        "dof": len(code.coordinates), "coordinates": ", ".join(code.coordinates),
    }
    free = [{"name": p.name, "default": repr(p.default), "unit": p.unit, "doc": p.doc}
            for p in code.parameters if not p.fixed]
    fixed = [f"{p.name} = {p.default!r}" for p in code.parameters if p.fixed]
    header_name = f"{code.name}.h"
    context = {"model": model, "functions": functions, "free_parameters": free,
               "fixed_parameters": _comment_lines(", ".join(fixed)) if fixed else [],
               "header_name": header_name, "float32": code.float32}
    return {
        header_name: render(HEADER_TEMPLATE, provenance=provenance(HEADER_TEMPLATE, code.name, code.hash), **context),
        f"{code.name}.c": render(SOURCE_TEMPLATE, provenance=provenance(SOURCE_TEMPLATE, code.name, code.hash),
                                 **context),
    }


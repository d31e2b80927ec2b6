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
* ``<model>_<function>_packed(const double *in, double *out)``: the inputs packed one after
  the other (vector elements, then parameters), the outputs one after the other;
* with the float32 option, ``..._f32`` variants of all three take and return ``float``.

Both print the same statements (so they return the same bits).  The single function runs
them once on scalars; the batch function runs them in a loop over the lanes of a block of
BLOCK configurations whose inputs were transposed into lane-contiguous arrays: a loop of
straight-line arithmetic the compiler vectorizes.  sin and cos of input symbols (all of
them, after :func:`~symkin.optimize.passes.expand_trig_sums`) are computed before that loop
by the generated vectorizable ``sincos`` (:mod:`symkin.backends.c.trig`).  A function with
more than :data:`LANE_SLOTS` non-constant outputs gets no lane loop: its batch function calls
the single one per configuration (same statements, same bits), because compiling the lane
loop grows much faster than its size (see :data:`LANE_SLOTS`).  A column map
(:class:`~symkin.ir.spec.MapBlock`) is one loop over its columns in the single function (the
body's code once: the forward dynamics' derivatives then fit the L1 instruction cache) and
the same operations written out column by column in the lane loop (:func:`_column_loop`):
the same bits under ISO C's rounding; where the compiler may fuse a product with a sum of
another statement (``-ffp-contract=fast``), the loop's column values, passed through an
array, leave it fewer products to fuse than the written-out copies, so the two may differ
in the last bits (the planar 2R arm's: 4e-16 relative in one column).

The functions are grouped, in order, into translation units of about :data:`PART_OPS`
operations, each guarded by ``#if !defined(<MODEL>_PART) || <MODEL>_PART == k`` (its sincos
helper too, for the units that use it), which the build compiles in parallel
(:mod:`symkin.backends.c.build`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

import sympy

from symkin.backends.c.assembly import assembly_context
from symkin.backends.c.build import part_macro, parts_line
from symkin.backends.c.printer import C_TYPES, CPrinter
from symkin.backends.c.trig import constants
from symkin.backends.comments import block_comment, wrapped
from symkin.backends.layout import element_text, expressions, used_symbols
from symkin.backends.naming import c_symbol
from symkin.backends.templating import provenance, render
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import FunctionSpec, MapBlock, OptimizedFunction
from symkin.optimize.schedule import steps

HEADER_TEMPLATE = "c/header.h.j2"
SOURCE_TEMPLATE = "c/source.c.j2"
DOC_WIDTH = 86
#: Configurations per block of the batch entry points (a multiple of every SIMD width).
BLOCK = 8
#: Most non-constant outputs a batch function evaluates in a lane loop.  GCC's SLP vectorizer
#: (on at -O2 and -O3) grows superlinearly with the lane loop's stores times its statements:
#: Stewart's closure_jacobians (240 stored outputs, 1 008 temporaries) took over 700 s at -O3
#: in a lane loop (33 s with -fno-tree-slp-vectorize), 4 s as a single function.  Every other
#: example function stores at most 81 (UR10e scene) and keeps its lanes; whole-library build
#: times: benchmarks/bench_compile.py.
LANE_SLOTS = 128

#: Operations (counted once per printing of a function's statements) after which a translation
#: unit of the source is closed: smaller functions share a unit, so a build does not start a
#: compiler process for every few lines, while the large ones compile in parallel
#: (:mod:`symkin.backends.c.build`).
PART_OPS = 1500

#: (precision, function-name suffix) of each emitted variant.
VARIANTS = {"double": "", "float": "_f32"}


def _comment_lines(text: str, width: int = DOC_WIDTH) -> list[str]:
    """Lines of a ``/* */`` comment of ``text`` (free text made inert, :mod:`symkin.backends.comments`)."""
    return wrapped(text, width, block_comment) or [""]


def _inputs(spec: FunctionSpec, used: set[sympy.Symbol], macro: str) -> tuple[list, list, list]:
    """(vectors, params, scalars) contexts; scalars: every used scalar input and where it is read."""
    scalars: list[dict[str, Any]] = []
    vectors = []
    offset = 0
    for v in spec.vector_inputs:
        elements = []
        for k, s in enumerate(v.symbols):
            if s in used:
                elements.append({"local": str(s), "index": k})
                scalars.append({"symbol": s, "local": str(s), "single": f"{v.name}[{k}]",
                                "batch": f"{v.name}[_j * {len(v.symbols)} + {k}]"})
        vectors.append({
            "name": v.name, "size": len(v.symbols), "elements": elements, "offset": offset,
            "doc": _comment_lines(f"{v.name}[{len(v.symbols)}]: {v.doc}: "
                                  + element_text(v) + "."),
        })
        offset += len(v.symbols)
    params = []
    for k, p in enumerate(spec.parameter_inputs):
        unit = f" [{p.units[0]}]" if p.units[0] else ""
        params.append({"name": p.name, "offset": offset + k, "doc": _comment_lines(
            f"{p.name}: {p.doc or 'parameter'}{unit}; default {macro}_DEFAULT_{p.name} = {p.default_value!r}.")})
        if p.symbols[0] in used:
            scalars.append({"symbol": p.symbols[0], "local": p.name, "single": None,
                            "batch": f"params[_j * params_stride + {k}]"})
    for row, scalar in enumerate(scalars):
        scalar["row"] = row
    return vectors, params, scalars


def _trigonometry(f: OptimizedFunction, scalars: list[dict[str, Any]]) -> tuple[list, dict]:
    """(trig contexts, {sin(a)/cos(a): local symbol}) for the input symbols under sin and cos."""
    row_of = {s["symbol"]: s["row"] for s in scalars}
    calls = {call for e in expressions(f) for call in e.atoms(sympy.sin, sympy.cos) if call.args[0] in row_of}
    names = {}
    trig = []
    for k, a in enumerate(sorted({call.args[0] for call in calls}, key=sympy.default_sort_key)):
        names[sympy.sin(a)] = sympy.Symbol(f"_sin_{a}", real=True)
        names[sympy.cos(a)] = sympy.Symbol(f"_cos_{a}", real=True)
        trig.append({"angle": str(a), "row": row_of[a], "index": k,
                     "sin": f"_sin_{a}" if sympy.sin(a) in calls else None,
                     "cos": f"_cos_{a}" if sympy.cos(a) in calls else None})
    return trig, names


def _outputs(spec: FunctionSpec, f: OptimizedFunction, text: Callable[[sympy.Expr], str]) -> tuple[list, int]:
    """(output contexts, number of non-constant entries); each of those gets a lane-array slot."""
    outputs = []
    slots = 0
    offset = 0
    for out, entries in zip(spec.outputs, f.outputs):
        size = math.prod(out.shape)
        shape = " x ".join(map(str, out.shape)) or "scalar"
        order = ", row-major" if len(out.shape) == 2 else ""
        assignments = []
        for k, e in enumerate(entries):
            constant = not e.free_symbols
            assignments.append({"index": k, "code": text(e), "constant": constant, "zero": e == 0,
                                "slot": None if constant else slots})
            slots += 0 if constant else 1
        outputs.append({
            "name": out.name, "size": size, "assignments": assignments, "offset": offset,
            "doc": _comment_lines(f"{out.name}[{size}]: {shape}{order}; {out.doc}"
                                  + (f" [{out.unit}]" if out.unit else "") + "."),
        })
        offset += size
    return outputs, slots


def _statements(f: OptimizedFunction, outputs: list[dict], text: Callable[[sympy.Expr], str]) -> list[dict]:
    """The temporaries with each output entry's store right after the last temporary it uses
    (:func:`symkin.optimize.schedule.steps`): in the temporaries' demand order a value stored is no longer live, so
    fewer are held in registers or spilled (:mod:`symkin.optimize.schedule`).  A column map's run of temporaries
    is one loop over its columns instead (:func:`_column_loop`), its arrays declared first and each column value
    written into them where it is computed (so it is not held until the loop)."""
    temporaries = {symbol for symbol, _ in f.temporaries}
    feeds: dict[sympy.Symbol, list[str]] = {}
    statements = []
    for number, block in enumerate(f.maps):
        fills = []
        for c, column in enumerate(block.columns):
            for k, value in enumerate(column):
                element = f"_map{number}_in[{k}][{c}]"
                if value in temporaries:
                    feeds.setdefault(value, []).append(element)
                else:  # a number or an input
                    fills.append({"element": element, "code": text(value)})
        statements.append({"store": False, "declare": {"name": f"_map{number}", "rows": len(block.parameters),
                                                       "count": len(block.columns), "results": len(block.results),
                                                       "fills": fills}})
    blocks = {block.start: (number, block) for number, block in enumerate(f.maps)}
    results = {t: f"_map{number}_out[{k}][{c}]" for number, block in enumerate(f.maps)
               for c, column in enumerate(block.targets) for k, t in enumerate(column) if t in temporaries}
    skip_below = 0
    for step in steps(f):
        if step.kind == "temporary":
            if step.number in blocks:
                number, block = blocks[step.number]
                statements.append({"store": False, "map": _column_loop(number, block, text)})
                skip_below = block.stop
            symbol, value = f.temporaries[step.number]
            if step.number < skip_below:  # the loop computed it: a result is read from its array where it is due
                if symbol in results:
                    statements.append({"store": False, "name": str(symbol), "code": results[symbol], "feeds": []})
                continue
            statements.append({"store": False, "name": str(symbol), "code": text(value),
                               "feeds": feeds.get(symbol, [])})
        elif step.kind == "store":
            output = outputs[step.number]
            statements.append({"store": True, "output": output["name"], **output["assignments"][step.entry]})
    return statements


def _column_loop(number: int, block: MapBlock, text: Callable[[sympy.Expr], str]) -> dict[str, Any]:
    """The context of map ``number``'s loop over the columns of ``_map<number>_in[k][r]`` (one row per parameter,
    the columns along it: the loop reads and writes contiguous columns, so the compiler vectorizes it): the body
    once, each result into ``_map<number>_out[m][r]``, which the function reads where the unrolled code would
    compute that result (:func:`_statements`).

    ``columns`` is the same loop written out column by column for the batch's lane loop (a loop inside it would
    keep the compiler from vectorizing the lanes): the body's code with its names suffixed ``_c<column>`` and the
    column's values for its parameters, the very operations of the loop in the same order, so that a batch returns
    the single calls' bits."""
    body = [{"name": str(s), "code": text(e)} for s, e in block.body]
    stores = [text(r) for r in block.results]
    own = re.compile(r"\b(" + "|".join(re.escape(str(s)) for s in (*block.parameters, *(s for s, _ in block.body)))
                     + r")\b")
    columns = []
    for c, column in enumerate(block.columns):
        suffix = f"_c{c}"
        parameters = [{"name": f"{p}{suffix}", "code": text(v)} for p, v in zip(block.parameters, column)]
        columns.append({"parameters": parameters,
                        "body": [{"name": b["name"] + suffix, "code": own.sub(r"\1" + suffix, b["code"])}
                                 for b in body],
                        "stores": [own.sub(r"\1" + suffix, code) for code in stores]})
    return {"name": f"_map{number}", "count": len(block.columns), "parameters": [str(p) for p in block.parameters],
            "body": body, "stores": stores, "columns": columns}


def _function_context(code: ModelCode, f: OptimizedFunction, precision: str, printer: CPrinter) -> dict[str, Any]:
    spec = f.spec
    suffix = VARIANTS[precision]
    used = used_symbols(f)
    vectors, params, scalars = _inputs(spec, used, code.name.upper())
    trig, trig_names = _trigonometry(f, scalars)

    def text(e: sympy.Expr) -> str:
        return printer.doprint(e.xreplace(trig_names) if trig_names else e)

    direct = {s for e in expressions(f) for s in (e.xreplace(trig_names) if trig_names else e).free_symbols}
    for scalar in scalars:
        scalar["direct"] = scalar["symbol"] in direct  # used other than through its sin/cos
    outputs, slots = _outputs(spec, f, text)
    return {
        "name": spec.name,
        "symbol": c_symbol(code.name, spec.name, suffix),
        "batch_symbol": c_symbol(code.name, spec.name, "_batch" + suffix),
        "packed_symbol": c_symbol(code.name, spec.name, "_packed" + suffix),
        "real": C_TYPES[precision],
        "sincos": f"{code.name}_sincos{suffix}",
        "summary": _comment_lines(spec.summary),
        "doc": _comment_lines(spec.doc),
        "vectors": vectors,
        "params": params,
        "scalars": scalars,
        "trig": trig,
        "outputs": outputs,
        "slots": slots,
        # lane arrays of the batch function: inputs, outputs, and angle/sin/cos per angle
        "batch_stack_bytes": (len(scalars) + slots + 3 * len(trig)) * BLOCK * (4 if precision == "float" else 8),
        "lanes": slots <= LANE_SLOTS,
        "statements": _statements(f, outputs, text),
        "op_count": f.op_counts["cse"],
    }


def _sincos_context(code: ModelCode, precision: str, printer: CPrinter) -> dict[str, Any]:
    c = constants(precision)
    float_suffix = "f" if precision == "float" else ""
    return {
        "name": f"{code.name}_sincos{VARIANTS[precision]}",
        "real": C_TYPES[precision],
        "fabs": "fabs" + float_suffix, "sin": "sin" + float_suffix, "cos": "cos" + float_suffix,
        "two_over_pi": printer.literal(c.two_over_pi),
        "parts": [printer.literal(p) for p in c.pi_half_parts],
        "magic": printer.literal(c.round_magic),
        "limit": printer.literal(c.limit),
        "sin_coefficients": [printer.literal(v) for v in c.sin_coefficients],
        "cos_coefficients": [printer.literal(v) for v in c.cos_coefficients],
        "literal": {v: printer.literal(float(v)) for v in (0.5, 1.5, -0.5, -1.5, 1.0, 4.0, 0.25)},
    }


def _assign_parts(functions: list[dict[str, Any]]) -> int:
    """Group the functions, in order, into translation units of about :data:`PART_OPS` operations
    (a larger function is a unit of its own); set each function's ``part`` and return the count."""
    part, size = 0, 0
    for function in functions:
        if size >= PART_OPS:
            part, size = part + 1, 0
        function["part"] = part
        size += function["op_count"] * (2 if function["lanes"] else 1)  # statements printed twice with lanes
    return part + 1


def emit_sources(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>.h: header, <model>.c: source} for ``code``."""
    precisions = ["double", "float"] if code.float32 else ["double"]
    printers = {p: CPrinter(p) for p in precisions}
    functions = [_function_context(code, f, precision, printers[precision])
                 for precision in precisions for f in code.functions]
    model = {
        "name": code.name, "macro": code.name.upper(), "hash": code.hash,
        "description": _comment_lines(code.description or code.name),
        "dof": len(code.coordinates), "coordinates": ", ".join(code.coordinates),
    }
    free = [{"name": p.name, "default": repr(p.default), "unit": block_comment(p.unit),
             "doc": block_comment(p.doc)}
            for p in code.parameters if not p.fixed]
    fixed = [f"{p.name} = {p.default!r}" for p in code.parameters if p.fixed]
    parts = _assign_parts(functions)
    sincos = []
    for precision in precisions:
        users = [f["part"] for f in functions if f["trig"] and f["real"] == C_TYPES[precision]]
        if users:
            sincos.append(_sincos_context(code, precision, printers[precision]) | {"units": users})
    header_name = f"{code.name}.h"
    context = {"model": model, "functions": functions, "free_parameters": free,
               "fixed_parameters": _comment_lines(", ".join(fixed)) if fixed else [],
               "header_name": header_name, "float32": code.float32, "block": BLOCK,
               "part_macro": part_macro(code.name), "parts": parts,
               "parts_line": parts_line(code.name, parts), "sincos": sincos,
               "assembly": assembly_context(functions, code.name)}
    return {
        header_name: render(HEADER_TEMPLATE, provenance=provenance(HEADER_TEMPLATE, code.name, code.hash), **context),
        f"{code.name}.c": render(SOURCE_TEMPLATE, provenance=provenance(SOURCE_TEMPLATE, code.name, code.hash),
                                 **context),
    }

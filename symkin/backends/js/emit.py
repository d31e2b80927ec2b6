"""Printing of the JavaScript module from the optimized functions (see templates/js/module.js.j2).

Calling convention (documented in the generated file):

* ``fk(q, params)``: each vector input as an array of its n numbers, then an optional object
  of parameter values (``{a: 0.12}``); a parameter left out takes the model's default, an
  unknown name throws;
* a function with one output returns it, one with several an object of its named outputs;
  an output of shape () is a number, (n,) an array, (r, c) an array of r rows: the shapes of
  the numpy backend without the batch axes.

One configuration per call, in IEEE doubles: the same statements as the other backends print,
so a value differs from numpy's only by the last-bit differences of the libraries' sin, cos and
atan2 (each within one ulp).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from symkin.backends.c.assembly import CLOSED
from symkin.backends.comments import block_comment, wrapped
from symkin.backends.js.printer import JsPrinter
from symkin.backends.layout import element_text, used_symbols
from symkin.backends.templating import provenance, render
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import InputSpec, OptimizedFunction
from symkin.newton import STALL_DECREASE

TEMPLATE = "js/module.js.j2"
DOC_WIDTH = 88


def _nested(shape: tuple[int, ...], codes: list[str]) -> str:
    """Array literal of ``codes`` (row-major) nested to ``shape``; a scalar is its code."""
    if not shape:
        return codes[0]
    step = len(codes) // shape[0]
    return "[" + ", ".join(_nested(shape[1:], codes[k * step:(k + 1) * step]) for k in range(shape[0])) + "]"


def _js_type(shape: tuple[int, ...]) -> str:
    return "number" + "[]" * len(shape)


def _input_doc(i: InputSpec) -> str:
    if i.kind == "parameter":
        unit = f" [{i.units[0]}]" if i.units[0] else ""
        return f"{i.name}: {i.doc or 'parameter'}{unit}; default {i.default_value!r}."
    return f"{i.doc}, {len(i.symbols)} numbers: {element_text(i)}."


def _function_context(f: OptimizedFunction, printer: JsPrinter) -> dict[str, Any]:
    spec = f.spec
    used = used_symbols(f)
    vectors = [{"name": v.name, "size": len(v.symbols),
                "doc": wrapped(_input_doc(v), DOC_WIDTH - len(v.name) - 20, block_comment),
                "elements": [{"local": printer.doprint(s), "index": k} for k, s in enumerate(v.symbols) if s in used]}
               for v in spec.vector_inputs]
    params = [{"name": p.name, "local": printer.doprint(p.symbols[0]), "default": printer.literal(p.default_value),
               "doc": block_comment(_input_doc(p))} for p in spec.parameter_inputs]
    outputs = []
    for out, entries in zip(spec.outputs, f.outputs):
        codes = [printer.doprint(e) for e in entries]
        outputs.append({"name": out.name, "value": _nested(tuple(out.shape), codes), "type": _js_type(tuple(out.shape)),
                        "doc": wrapped(f"{out.name}: shape {tuple(out.shape)}; "
                                       f"{out.doc}" + (f" [{out.unit}]" if out.unit else "") + ".",
                                       DOC_WIDTH - 10, block_comment)})
    multi = len(spec.outputs) > 1
    returns = ("{" + ", ".join(f"{o['name']}: {o['type']}" for o in outputs) + "}") if multi else outputs[0]["type"]
    return {
        "name": spec.name,
        "summary": block_comment(spec.summary),
        "doc_lines": wrapped(spec.doc, DOC_WIDTH - 3, block_comment),
        "vectors": vectors,
        "params": params,
        "param_names": json.dumps([p.name for p in spec.parameter_inputs]),
        "temporaries": [{"name": printer.doprint(s), "code": printer.doprint(e)} for s, e in f.temporaries],
        "outputs": outputs,
        "multi": multi,
        "returns": returns,
        "signature": ", ".join([v.name for v in spec.vector_inputs] + (["params"] if params else [])),
        "metadata": json.dumps({
            "inputs": [v.name for v in spec.vector_inputs],
            "parameters": [p.name for p in spec.parameter_inputs],
            "outputs": {o.name: list(o.shape) for o in spec.outputs},
        }, separators=(", ", ": ")),
    }


def _assembly_context(functions: Sequence[OptimizedFunction]) -> dict[str, str] | None:
    """The template's ``assembly`` (the generated solvers ``assemble``, ``assembly_jacobian`` and ``assemble_inverse``,
    the C backend's): the parameters of ``closure`` and ``closure_jacobians`` (JSON lists) and the closing rule's
    factor (:data:`symkin.backends.c.assembly.CLOSED`), or None where the script has not both."""
    by_name = {f.spec.name: f.spec for f in functions}
    if not {"closure", "closure_jacobians"} <= set(by_name):
        return None
    return {key: json.dumps([p.name for p in by_name[name].parameter_inputs])
            for key, name in (("closure_params", "closure"), ("jacobian_params", "closure_jacobians"))} | {
        "closed": repr(CLOSED)}


def emit_script(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>.js: script text} for ``code``; with ``closure`` and ``closure_jacobians`` also ``assemble`` and
    ``assembly_jacobian`` (the forward kinematics warm-started and J = dp/dq, the C backend's ``<model>_assemble`` and
    ``<model>_assembly_jacobian``) and ``assemble_inverse`` (Gauss-Newton for the joints at a platform pose, the C
    backend's ``<model>_assemble_inverse``): the viewer's solvers."""
    printer = JsPrinter()
    free = [p for p in code.parameters if not p.fixed]
    text = render(
        TEMPLATE,
        provenance=provenance(TEMPLATE, code.name, code.hash),
        model={"name": code.name, "hash": code.hash,
               "description": wrapped(code.description or code.name, DOC_WIDTH - 3, block_comment),
               "symkin_version": code.symkin_version},
        coordinates=json.dumps(list(code.coordinates)),
        parameters=[{"name": p.name, "default": printer.literal(p.default)} for p in free],
        functions=[_function_context(f, printer) for f in code.functions],
        name_json=json.dumps(code.name), hash_json=json.dumps(code.hash),
        version_json=json.dumps(code.symkin_version),
        assembly=_assembly_context(code.functions), stall_decrease=repr(STALL_DECREASE),
    )
    return {f"{code.name}.js": text}


"""Printing of the numpy module from the optimized functions (see templates/numpy/module.py.j2)."""

from __future__ import annotations

from typing import Any

from symkin.backends.comments import docstring, plain, wrapped
from symkin.backends.layout import element_indices, element_text, shape_text, type_name
from symkin.backends.numpy.printer import BatchNumPyPrinter
from symkin.backends.templating import provenance, render
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import InputSpec, OptimizedFunction
from symkin.optimize.schedule import steps

TEMPLATE = "numpy/module.py.j2"
#: Configurations per chunk of large batches (temporaries of a 6-DoF chunk fit in L2).
CHUNK = 4096
DOC_WIDTH = 84


def _wrap(text: str, indent: str = "    ") -> list[str]:
    """Docstring lines of ``text`` (free text made inert, :mod:`symkin.backends.comments`), later ones indented."""
    lines = wrapped(text, DOC_WIDTH, docstring)
    return lines[:1] + [indent + line for line in lines[1:]]


def _input_doc(i: InputSpec) -> list[str]:
    if i.kind == "parameter":
        unit = f" [{i.units[0]}]" if i.units[0] else ""
        return _wrap(f"{i.name}: {i.doc or 'parameter'}{unit}; default {i.default_value!r}; "
                     "a scalar or an array broadcastable to the batch shape.")
    return _wrap(f"{i.name}: {i.doc}, shape (..., {len(i.symbols)}): {element_text(i)}.")


def _statements(f: OptimizedFunction, temporaries: list[dict], outputs: list[dict]) -> list[dict]:
    """The temporaries, each output entry stored right after the last temporary it uses and each temporary deleted
    after its last use (:func:`symkin.optimize.schedule.steps`): a batch then holds few arrays at once (the UR10e's
    inverse-dynamics derivatives: at most 235 of their 686 temporaries instead of all; 1 737 ns per configuration
    instead of 2 528 in ``benchmarks/bench_eval.py``'s numpy batch column), which keeps a chunk's arrays in the
    caches.  Bit for bit the same values."""
    statements = []
    for step in steps(f):
        if step.kind == "temporary":
            statements.append({"kind": "temporary", **temporaries[step.number]})
        elif step.kind == "dead":
            statements.append({"kind": "delete", "names": ", ".join(temporaries[k]["name"] for k in step.dead)})
        else:
            output = outputs[step.number]
            code = output["entries"][step.entry]
            if code is not None:                                    # an identically zero entry stays zeros' 0
                statements.append({"kind": "store", "local": output["local"], "index": output["indices"][step.entry],
                                   "code": code})
    return statements


def function_context(f: OptimizedFunction, printer: BatchNumPyPrinter) -> dict[str, Any]:
    """What the module templates (numpy, JAX) say of one function: signature, docstring, inputs, temporaries,
    outputs (every entry row-major, printed, and its index), and numpy's statements
    (:func:`_statements`), printed by ``printer``."""
    spec = f.spec
    vectors = spec.vector_inputs
    params = spec.parameter_inputs
    signature = ", ".join([v.name for v in vectors] + (["*"] if params else [])
                          + [f"{p.name}={p.default_value!r}" for p in params])
    outputs = []
    for out, entries in zip(spec.outputs, f.outputs):
        printed = [None if e == 0 else printer.doprint(e) for e in entries]  # row-major; None: identically zero
        outputs.append({
            "name": out.name,
            "local": f"_out_{out.name}",
            "shape": repr(tuple(out.shape)),
            "entries": printed,  # the JAX template stacks them
            "indices": [", ".join(["..."] + [str(k) for k in index]) for index in element_indices(out.shape)],
        })
    returns = [line for out in spec.outputs
               for line in _wrap(f"{out.name}: shape {shape_text(out.shape)}; {out.doc}"
                                 + (f" [{out.unit}]" if out.unit else "") + ".")]
    multi = len(spec.outputs) > 1
    temporaries = [{"name": str(s), "code": printer.doprint(e)} for s, e in f.temporaries]
    return {
        "name": spec.name,
        "summary": docstring(spec.summary),
        "doc_lines": wrapped(spec.doc, DOC_WIDTH, docstring),
        "signature": signature,
        "signature_short": ", ".join(v.name for v in vectors) + (", **params" if params else ""),
        "returns_short": (type_name(spec.name) + "(" + ", ".join(o.name for o in spec.outputs) + ")") if multi
        else f"{spec.outputs[0].name} {shape_text(spec.outputs[0].shape)}",
        "args_doc": [line for i in spec.inputs for line in _input_doc(i)],
        "returns_doc": returns if not multi else [f"{type_name(spec.name)} with the fields:"] + returns,
        "vectors": [{"name": v.name, "size": len(v.symbols),
                     "elements": [{"local": str(s), "index": k} for k, s in enumerate(v.symbols)]} for v in vectors],
        "batch_shapes": ([f"{v.name}.shape[:-1]" for v in vectors]
                         + [f"{printer.array_module}.shape({p.name})" for p in params]),
        "temporaries": temporaries,
        "statements": _statements(f, temporaries, outputs),
        "outputs": outputs,
        "result_type": type_name(spec.name) if multi else "",
        "params": [p.name for p in params],
    }


def module_context(code: ModelCode, template: str) -> dict[str, Any]:
    """What the module templates (numpy, JAX) say of the model: provenance, name, hash, description, coordinates
    and the free parameters' defaults."""
    return {
        "provenance": provenance(template, code.name, code.hash),
        "model": {"name": code.name, "hash": code.hash,
                  "description": plain(code.description or code.name, keep_newlines=True),
                  "symkin_version": code.symkin_version, "coordinates": code.coordinates},
        "free_parameters": [{"name": p.name, "default_text": repr(p.default)} for p in code.parameters
                            if not p.fixed],
    }


def emit_module(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>.py: module text} for ``code``."""
    printer = BatchNumPyPrinter()
    text = render(TEMPLATE, **module_context(code, TEMPLATE), array=printer.array_module, chunk=CHUNK,
                  functions=[function_context(f, printer) for f in code.functions])
    return {f"{code.name}.py": text}

"""Compiled CPython entry points of the C backend: one-configuration calls at C speed (issue 34).

A ctypes call spends about a microsecond in the binding (argument conversion, checks, allocation) around a
C function that takes tens of nanoseconds.  Here every generated function gets a ``METH_FASTCALL`` function of
an extension module rendered from the manifest (``templates/c/python_module.c.j2``) and linked to the model's
library: a call with one configuration (each vector a float64 C-contiguous ndarray of its exact shape, or a
list or tuple of floats), parameters as Python floats or ints, and optionally ``out=`` (an array, or a tuple
of arrays for several outputs, written in place) is evaluated without leaving C; every other call is passed
on, with the same arguments, to the ctypes binding's Python function (:func:`symkin.runtime.wrappers.wrap_function`),
so batches, broadcasting, conversions and the numpy backend's errors stay as they are, and ``out=`` then
receives a copy of the result.  The extension is built by the C backend's cached, locked build
(:func:`symkin.backends.c.build.extension_module`); without Python's or numpy's headers, or if the build fails,
the functions stay the ctypes ones and a line on stderr says why.  ``SYMKIN_C_ENTRY=ctypes`` chooses ctypes.
"""

from __future__ import annotations

import dataclasses
import importlib.machinery
import importlib.util
import json
import os
import sys
from collections.abc import Callable, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from symkin._version import __version__
from symkin.backends.c.build import extension_module, progress, python_include_directories
from symkin.backends.naming import c_symbol
from symkin.errors import GeneratedCodeError
from symkin.manifest_schema import Function
from symkin.runtime.wrappers import signature_text

#: Environment variable: ``ctypes`` keeps the ctypes functions (no extension module is built).
ENTRY_VARIABLE = "SYMKIN_C_ENTRY"
#: The extension module's template (under templates/).
TEMPLATE = "c/python_module.c.j2"
#: The template of the generated assembly's extension module (:func:`assembly_entry_points`).
ASSEMBLY_TEMPLATE = "c/assembly_module.c.j2"
#: The array checks both templates include.
ARRAYS_TEMPLATE = "c/float64_arrays.c.j2"


def c_string(text: str) -> str:
    """``text`` as a C string literal: printable ASCII as it is, every other byte (and quote, backslash, '?')
    as a three-digit octal escape, so that no text from a model file can end the literal or form a trigraph."""
    out = []
    for byte in text.encode("utf-8"):
        char = chr(byte)
        out.append(char if 0x20 <= byte < 0x7F and char not in '"\\?' else f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def c_double(value: float) -> str:
    """An exact C99 literal of ``value`` (hexadecimal; HUGE_VAL and NAN for the non-finite)."""
    if value != value:
        return "NAN"
    if value in (float("inf"), float("-inf")):
        return "HUGE_VAL" if value > 0 else "-HUGE_VAL"
    return value.hex()


def _identifiers(names: Sequence[str]) -> None:
    """Refuse a manifest name that is no ASCII identifier: it is written into C source."""
    for name in names:
        if not name.isidentifier() or not name.isascii():
            raise GeneratedCodeError(f"the manifest names {name!r}, which is no identifier")


def _function(index: int, model: str, record: Function, docstring: str) -> dict[str, Any]:
    """What the template needs of one manifest function."""
    vectors = [i.size for i in record.vector_inputs]
    _identifiers([i.name for i in record.inputs] + [record.name])
    arguments, vector, parameter = [], 0, 0
    for i in record.inputs:
        if i.is_parameter:
            arguments.append(f"p[{parameter}]")
            parameter += 1
        else:
            arguments.append(f"v[{vector}]")
            vector += 1
    outputs = [{"dims": list(o.shape)} for o in record.results]
    shapes = ", ".join(str(tuple(o["dims"])) for o in outputs)
    needs = (f"a writeable float64 C-contiguous array of shape {shapes}" if len(outputs) == 1 else
             f"a tuple of {len(outputs)} writeable float64 C-contiguous arrays of shapes {shapes}")
    signature = signature_text(record)
    keywords = "out=None" if "*" in signature else "*, out=None"
    doc = f"{record.name}($module, {signature + ', ' if signature else ''}{keywords})\n--\n\n{docstring}"
    return {"index": index, "name": record.name, "symbol": c_symbol(model, record.name),
            "inputs": record.inputs, "vectors": vectors, "offsets": [sum(vectors[:k]) for k in range(len(vectors))],
            "buffer_size": sum(vectors), "parameters": list(record.parameters),
            "defaults": [c_double(i.default) for i in record.parameter_inputs],
            "arguments": arguments, "outputs": outputs,
            "out_message": c_string(f"{record.name}(): out= must be {needs} (for one configuration; for a batch, "
                                    "the batch shape first)"),
            "doc": c_string(doc)}


def module_source(model: str, header: str, records: Sequence[Function], docstrings: list[str]) -> str:
    """The extension module's C source for the manifest functions ``records``."""
    functions = [_function(k, model, record, doc) for k, (record, doc) in enumerate(zip(records, docstrings))]
    from symkin.backends.templating import render  # jinja2: only when the extension is built

    return render(TEMPLATE, model=model, header=header, version=__version__, functions=functions,
                  max_outputs=max((len(r.results) for r in records), default=1))


def _source_inputs(model: str, header: str, records: Sequence[Function], docstrings: list[str]) -> bytes:
    """Everything :func:`module_source` renders from (this module, the template, the functions), so that a cached
    extension is found without rendering its source (loading imports no jinja2)."""
    functions = json.dumps([model, header, __version__, [dataclasses.asdict(r) for r in records], docstrings],
                           sort_keys=True).encode()
    return b"\0".join([Path(__file__).read_bytes(), *_templates(TEMPLATE), functions])


def _templates(name: str) -> list[bytes]:
    """The bytes of the template ``name`` and of the array checks it includes (a cached extension's key)."""
    folder = resources.files("symkin.templates")
    return [folder.joinpath(name).read_bytes(), folder.joinpath(ARRAYS_TEMPLATE).read_bytes()]


def entry_points(library: Path, header: Path, model: str, records: Sequence[Function],
                 functions: dict[str, Callable[..., Any]]) -> dict[str, Callable[..., Any]] | None:
    """The compiled function of every manifest function (each passing what it does not take to ``functions``,
    the ctypes ones), or None where there is no extension (chosen off, no headers, a failed build: said on
    stderr)."""
    if os.environ.get(ENTRY_VARIABLE, "") == "ctypes":
        return None
    if python_include_directories() is None:
        progress(f"symkin: no Python or numpy C headers for {sys.executable}; {model}'s Python calls go through ctypes "
             "(install the Python development package, e.g. python3-dev, for the compiled entry points)")
        return None
    docstrings = [functions[r.name].__doc__ or "" for r in records]
    try:
        path, name = extension_module(lambda: module_source(model, header.name, records, docstrings),
                                      _source_inputs(model, header.name, records, docstrings), model, header, library)
    except GeneratedCodeError as err:
        progress(f"symkin: the compiled entry points of {model} did not build; its Python calls go through ctypes:\n{err}")
        return None
    module = _import(path, name)
    if module is None:
        return None
    python = tuple(functions[r.name] for r in records)
    module._bind(python, tuple(getattr(f, "result_type", None) for f in python))
    return {record.name: getattr(module, record.name) for record in records}


def _import(path: Path, name: str) -> Any:
    """The extension module ``name`` built at ``path``, imported (None where Python finds no loader for it)."""
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, str(path), loader=loader)
    if spec is None:
        return None
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def assembly_entry_points(library: Path, header: Path, model: str, sizes: dict[str, int],
                          parameters: Sequence[str], dynamics_parameters: Sequence[str] | None = None) -> Any:
    """The extension module of the generated assembly of ``model`` (:mod:`symkin.backends.c.assembly`): its
    ``assemble(q, s, p, parameters, max_iterations, tolerance, residual)`` and ``jacobian(q, s, p, parameters, J)``
    (and, with ``dynamics_parameters``, ``dynamics(q, s, p, qd, parameters, M, bias, W, drift, u)``) call the C
    functions without ctypes and return None for an argument they do not take (the caller's checks then say what is
    wrong).  ``sizes``: the closure's n, ns and np (keys q, s, p); ``parameters``: the assembly's free parameters in
    its order; ``dynamics_parameters``: ``<model>_actuated_dynamics``' (None: the library has none).  None where there
    is no extension (chosen off, no headers, a failed build: said on stderr)."""
    if os.environ.get(ENTRY_VARIABLE, "") == "ctypes" or python_include_directories() is None:
        return None
    _identifiers([model, *parameters, *(dynamics_parameters or ())])
    context = {"model": model, "header": header.name, "version": __version__, "assemble": f"{model}_assemble",
               "jacobian": f"{model}_assembly_jacobian", "n": sizes["q"], "ns": sizes["s"], "np": sizes["p"],
               "parameters": list(parameters),
               "dynamics": None if dynamics_parameters is None else f"{model}_actuated_dynamics",
               "dynamics_parameters": list(dynamics_parameters or ())}

    def source() -> str:
        from symkin.backends.templating import render  # jinja2: only when the extension is built

        return render(ASSEMBLY_TEMPLATE, **context)

    what = b"\0".join([Path(__file__).read_bytes(), *_templates(ASSEMBLY_TEMPLATE),
                       json.dumps(context, sort_keys=True).encode()])
    try:
        path, name = extension_module(source, what, f"{model}_assembly", header, library)
    except GeneratedCodeError as err:
        progress(f"symkin: the compiled assembly entry points of {model} did not build; its calls go through "
                 f"ctypes:\n{err}")
        return None
    return _import(path, name)

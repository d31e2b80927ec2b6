"""ctypes binding of a compiled model library to Python functions (no sympy needed).

A call with one configuration and scalar parameters goes to ``<model>_<function>_packed``
through the per-thread packed arrays of :mod:`symkin.runtime.packed`: two pointer arguments
keep the ctypes call cheap.  Any other call
goes to ``<model>_<function>_batch``: vector inputs broadcast to the batch shape and made
C-contiguous (n x size), parameters packed into one array (stride 0 when all are scalars,
else one row per configuration), all outputs in one fresh buffer, output k being the
contiguous block of n * size_k doubles at offset n * offset_k.
"""

from __future__ import annotations

import ctypes
import functools
import math
from pathlib import Path
from typing import Any

import numpy

from symkin.backends.c.loader_assembly import CompiledFunctions, bind_assembly
from symkin.backends.c.build import shared_library
from symkin.backends.naming import c_symbol
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import Function, ModelInfo
from symkin.backends.c.loader_entry_points import entry_points
from symkin.runtime.packed import single_kernel
from symkin.runtime.wrappers import Kernel, SingleKernel, wrap_function

DOUBLE_SIZE = 8


def source_and_header(directory: Path, files: tuple[str, ...]) -> tuple[Path, Path]:
    """The C source and header among the files the C backend emitted."""
    sources = [directory / f for f in files if f.endswith(".c")]
    headers = [directory / f for f in files if f.endswith(".h")]
    if len(sources) != 1 or len(headers) != 1:
        raise GeneratedCodeError(f"{directory}: the manifest lists no C source and header pair (found {files})")
    for path in sources + headers:
        if not path.exists():
            raise GeneratedCodeError(f"{path} is missing; derive the model again with --backend c")
    return sources[0], headers[0]


def _entry(library: ctypes.CDLL, symbol: str, argtypes: list[Any]) -> Any:
    try:
        entry = getattr(library, symbol)
    except AttributeError:
        raise GeneratedCodeError(f"the compiled library has no function {symbol}; derive the model again") from None
    entry.argtypes = argtypes
    entry.restype = None
    return entry


def _kernels(library: ctypes.CDLL, model: str, record: Function) -> tuple[Kernel, SingleKernel]:
    vector_sizes = [i.size for i in record.vector_inputs]
    n_params = len(record.parameter_inputs)
    output_shapes = [o.shape for o in record.results]
    sizes = [math.prod(shape) for shape in output_shapes]
    offsets = [sum(sizes[:k]) for k in range(len(sizes))]
    total = sum(sizes)
    pointers = [ctypes.c_void_p] * len(vector_sizes)
    outputs = [ctypes.c_void_p] * len(output_shapes)
    packed = _entry(library, c_symbol(model, record.name, "_packed"), [ctypes.c_void_p, ctypes.c_void_p])
    batched = _entry(library, c_symbol(model, record.name, "_batch"),
                     [ctypes.c_size_t] + pointers + ([ctypes.c_void_p, ctypes.c_size_t] if n_params else []) + outputs)

    def split(buffer: numpy.ndarray, n: int, batch: tuple[int, ...]) -> list[numpy.ndarray]:
        return [buffer[n * offset:n * (offset + size)].reshape(batch + shape)
                for offset, size, shape in zip(offsets, sizes, output_shapes)]

    def attach(packed_input: numpy.ndarray, packed_output: numpy.ndarray):
        return functools.partial(packed, packed_input.ctypes.data, packed_output.ctypes.data)

    views = [(slice(offset, offset + size), shape) for offset, size, shape in zip(offsets, sizes, output_shapes)]
    if len(views) == 1:
        shape = output_shapes[0]
        one = single_kernel(vector_sizes, n_params, total, attach, lambda out: [out.reshape(shape)])
    else:
        one = single_kernel(vector_sizes, n_params, total, attach,
                            lambda out: [out[part].reshape(shape) for part, shape in views])

    def kernel(batch: tuple[int, ...], vectors: list[numpy.ndarray], params: list[numpy.ndarray]) -> list[numpy.ndarray]:
        if not batch and all(p.ndim == 0 for p in params):
            return one(vectors, [float(p) for p in params])
        n = math.prod(batch)
        arguments: list[Any] = [n]
        keep = []  # arrays whose memory C reads, alive until the call returns
        for v, size in zip(vectors, vector_sizes):
            if v.shape[:-1] != batch or not v.flags.c_contiguous:
                v = numpy.ascontiguousarray(numpy.broadcast_to(v, batch + (size,)))
            keep.append(v)
            arguments.append(v.ctypes.data)
        if n_params:
            if all(p.ndim == 0 for p in params):
                rows, stride = numpy.array([float(p) for p in params]), 0
            else:
                rows = numpy.empty(batch + (n_params,))
                for k, p in enumerate(params):
                    rows[..., k] = p
                stride = n_params
            keep.append(rows)
            arguments += [rows.ctypes.data, stride]
        buffer = numpy.empty(n * total)
        address = buffer.ctypes.data
        arguments += [address + DOUBLE_SIZE * n * offset for offset in offsets]
        batched(*arguments)
        return split(buffer, n, batch)

    return kernel, one


def load(directory: Path, info: ModelInfo) -> dict[str, Any]:
    """Compile (or find in the cache) the model's C code and bind every function of the manifest: the compiled
    CPython entry points (:mod:`symkin.backends.c.loader_entry_points`) over the ctypes functions, or those alone;
    and the generated assembly's functions where the model has closure and closure_jacobians
    (:class:`symkin.backends.c.loader_assembly.CompiledFunctions`)."""
    source, header = source_and_header(directory, info.backend_files.get("c", ()))
    path = shared_library(source, header)
    library = ctypes.CDLL(str(path))
    model = info.name
    functions = {}
    records = tuple(info.functions.values())
    for record in records:
        kernel, one = _kernels(library, model, record)
        functions[record.name] = wrap_function(record, kernel, "c", single=one)
    bound = CompiledFunctions(entry_points(path, header, model, records, functions) or functions)
    # bound now: a model file derived on the fly loads from a scratch folder that is gone when the assembly is asked for
    bound.assembly = bind_assembly(library, path, header, info)
    return bound

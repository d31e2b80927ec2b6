"""Serialized CasADi functions wrapped with the numpy backend's calling semantics (no sympy).

Evaluation goes through CasADi's zero-copy ``Function.buffer()`` interface (passing numpy
memory directly; the ordinary call converts every argument to a DM and costs tens of
microseconds): one configuration calls the function itself through the packed arrays of
:mod:`symkin.runtime.packed`, a batch of n calls ``function.map(n)``.  CasADi is column-major, which fits numpy's batch layout: an
(n, size) C-ordered array is the size x n matrix ``map`` wants, and an r x c output of n
configurations (an r x c*n matrix) is the C-ordered array (n, c, r), transposed to
(n, r, c).  Buffers are kept per thread and per batch size (the last few sizes).
"""

from __future__ import annotations

import functools
import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import casadi
import numpy

from symkin.backends.naming import casadi_file, matrix_shape
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import Function, ModelInfo
from symkin.runtime.packed import single_kernel
from symkin.runtime.wrappers import Kernel, SingleKernel, wrap_function

#: How many batch sizes (mapped functions and their buffers) each function keeps per thread.
CACHE_SIZE = 4


class _Buffers(threading.local):
    """Per-thread ``(buffer, evaluate)`` pairs of one function, by batch size."""

    def __init__(self) -> None:
        self.by_size: OrderedDict[int, tuple[Any, Any]] = OrderedDict()


def _evaluate(buffer: Any, evaluate: Callable[[], None]) -> None:
    """Evaluate into the arrays ``buffer`` is bound to (holding ``buffer`` keeps it alive as long as they are)."""
    evaluate()


def _bind(packed: numpy.ndarray, sizes: list[int], setter: Any) -> list[numpy.ndarray]:
    """Consecutive slices of ``packed``, each handed to ``setter(k, memoryview)``."""
    views, start = [], 0
    for k, size in enumerate(sizes):
        views.append(packed[start:start + size])
        setter(k, views[-1].data)
        start += size
    return views


def _kernels(function: casadi.Function, record: Function) -> tuple[Kernel, SingleKernel]:
    vector_sizes = [i.size for i in record.vector_inputs]
    output_shapes = [o.shape for o in record.results]
    output_2d = [matrix_shape(shape) for shape in output_shapes]
    buffers = _Buffers()
    lock = threading.Lock()  # function.map is not known to be thread-safe

    def buffer_of(n: int) -> tuple[Any, Any]:
        cache = buffers.by_size
        if n in cache:
            cache.move_to_end(n)
            return cache[n]
        with lock:
            evaluated = function if n == 1 else function.map(n, "serial")
            cache[n] = evaluated.buffer()
        if len(cache) > CACHE_SIZE:
            cache.popitem(last=False)
        return cache[n]

    n_params = len(record.parameter_inputs)
    output_sizes = [rows * cols for rows, cols in output_2d]
    output_starts = [sum(output_sizes[:k]) for k in range(len(output_sizes))]

    def attach(packed_input: numpy.ndarray, packed_output: numpy.ndarray):
        """The unmapped function's buffer, bound once to this thread's packed arrays."""
        buffer, evaluate = function.buffer()
        _bind(packed_input, vector_sizes + [1] * n_params, buffer.set_arg)
        _bind(packed_output, output_sizes, buffer.set_res)
        return functools.partial(_evaluate, buffer, evaluate)

    def unpack(out: numpy.ndarray) -> list[numpy.ndarray]:
        """Column-major r x c blocks -> row-major outputs."""
        return [out[start:start + rows * cols].reshape(cols, rows).T.copy().reshape(shape) if cols > 1
                else out[start:start + rows].reshape(shape)
                for start, shape, (rows, cols) in zip(output_starts, output_shapes, output_2d)]

    one = single_kernel(vector_sizes, n_params, sum(output_sizes), attach, unpack)

    def kernel(batch: tuple[int, ...], vectors: list[numpy.ndarray], params: list[numpy.ndarray]) -> list[numpy.ndarray]:
        n = math.prod(batch)
        if n == 0:
            return [numpy.empty(batch + shape) for shape in output_shapes]
        buffer, evaluate = buffer_of(n)
        keep = [numpy.ascontiguousarray(numpy.broadcast_to(v, batch + (size,)))
                for v, size in zip(vectors, vector_sizes)]
        keep += [p if p.ndim == 0 and n == 1 else numpy.ascontiguousarray(numpy.broadcast_to(p, batch))
                 for p in params]
        for k, array in enumerate(keep):
            buffer.set_arg(k, array.data)
        raw = [numpy.empty((n, cols, rows)) for rows, cols in output_2d]
        for k, array in enumerate(raw):
            buffer.set_res(k, array.data)
        evaluate()
        return [numpy.ascontiguousarray(r.transpose(0, 2, 1)).reshape(batch + shape)
                for r, shape in zip(raw, output_shapes)]

    return kernel, one


def load(directory: Path, info: ModelInfo) -> dict[str, Any]:
    """Load every function of the manifest from its ``.casadi`` file and wrap it.

    Raises:
        GeneratedCodeError: a file is missing or does not hold the function the manifest names.
    """
    model = info.name
    functions = {}
    for record in info.functions.values():
        path = directory / casadi_file(model, record.name)
        if not path.exists():
            raise GeneratedCodeError(f"{path} is missing; derive the model again with --backend casadi")
        function = casadi.Function.load(str(path))
        expected = [i.name for i in record.inputs]
        if function.name() != record.name or function.name_in() != expected:
            raise GeneratedCodeError(f"{path} holds {function.name()}({', '.join(function.name_in())}), "
                                     f"not {record.name}({', '.join(expected)}); derive the model again")
        kernel, one = _kernels(function, record)
        wrapper = wrap_function(record, kernel, "casadi", single=one)
        setattr(wrapper, "casadi", function)  # the raw casadi.Function, for AD and codegen
        functions[record.name] = wrapper
    return functions


def casadi_function(model: Any, name: str) -> casadi.Function:
    """The ``casadi.Function`` behind the generated function ``name`` of a model loaded with ``backend="casadi"``
    (bound or not: a bound model wraps it in ``functools.partial``).

    Raises:
        ValueError: the model has no such CasADi function (not derived, or loaded with another backend).
    """
    function = getattr(model, name, None)
    function = getattr(function, "func", function)
    if function is None or not hasattr(function, "casadi"):
        raise ValueError(f"{model.name}: no CasADi function '{name}'; derive the model with --backend numpy,casadi")
    return function.casadi

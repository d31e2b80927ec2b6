"""The single-configuration fast path shared by the compiled backends (C, CasADi).

A control loop calls a generated function with one configuration and scalar parameters,
thousands of times a second; there the Python overhead around a sub-microsecond kernel is
the cost.  Each function keeps, per thread, one packed input array (the vector inputs, then
the parameters) and one packed output array, attached once to the backend's evaluator at
fixed addresses (asking numpy for an array's address costs about a microsecond, more than
the C code).  A call copies the inputs in, evaluates, and hands a copy of the outputs to the
backend's ``unpack`` (row-major C outputs are reshaped; CasADi's column-major ones are
transposed).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence

import numpy

from symkin.runtime.wrappers import SingleKernel

#: attach(packed input, packed output) -> a callable that evaluates the function from one into the other.
Attach = Callable[[numpy.ndarray, numpy.ndarray], Callable[[], object]]


class PackedArrays(threading.local):
    """Per-thread packed input and output arrays of one function, attached to its evaluator."""

    def __init__(self, vector_sizes: Sequence[int], n_params: int, output_size: int, attach: Attach):
        self.input = numpy.empty(sum(vector_sizes) + n_params)
        starts = [sum(vector_sizes[:k]) for k in range(len(vector_sizes))]
        self.vectors = [self.input[start:start + size] for start, size in zip(starts, vector_sizes)]
        self.output = numpy.empty(output_size)
        self.evaluate = attach(self.input, self.output)


def single_kernel(vector_sizes: Sequence[int], n_params: int, output_size: int, attach: Attach,
                  unpack: Callable[[numpy.ndarray], list[numpy.ndarray]]) -> SingleKernel:
    """``one(vectors, params) -> outputs`` through per-thread :class:`PackedArrays`.

    Args:
        vector_sizes: size of each vector input, in order.
        n_params: number of scalar parameters (after the vectors in the packed input).
        output_size: total size of the packed outputs.
        attach: binds a thread's packed arrays to the backend's evaluator.
        unpack: the packed outputs (a fresh copy) -> the output arrays.
    """
    scratch = PackedArrays(vector_sizes, n_params, output_size, attach)
    first_param = sum(vector_sizes)

    def one(vectors: Sequence[numpy.ndarray], params: Sequence[float]) -> list[numpy.ndarray]:
        local = scratch
        for target, v in zip(local.vectors, vectors):
            target[...] = v
        if params:
            local.input[first_param:] = params
        local.evaluate()
        return unpack(local.output.copy())

    return one

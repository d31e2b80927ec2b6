"""Python functions over compiled kernels, with the numpy backend's exact calling semantics.

The numpy backend's generated functions define the Python interface of every model:
``fk(q, *, l1=0.1, l2=0.1)`` with vector inputs of shape (..., n) and any leading batch
shape, keyword-only parameters that broadcast against the batch, outputs of shape
batch + output shape (a namedtuple when there are several), and ``ValueError`` messages
such as ``fk(): 'q' must have shape (..., 6), got (5,)``.  The C and CasADi loaders wrap
their kernels with :func:`wrap_function`, which gives them the same interface from the
manifest alone: the function is a real Python ``def`` (compiled from a signature built of
validated identifiers and float literals), so argument binding, ``inspect.signature``,
``functools.partial`` and the TypeErrors of a wrong call are those of the numpy module.

A kernel is ``kernel(batch, vectors, params) -> list of output arrays``, called with the
broadcast batch shape, the vector inputs as float64 arrays of shape (..., n) and the
parameters as float64 arrays (0-d when scalar), each broadcastable to the batch shape.
"""

from __future__ import annotations

import collections
import keyword
from collections.abc import Callable, Sequence
from typing import Any

import numpy

from symkin.backends.naming import shape_text, type_name
from symkin.errors import GeneratedCodeError
from symkin.manifest_schema import Function

Kernel = Callable[[tuple[int, ...], list[numpy.ndarray], list[numpy.ndarray]], list[numpy.ndarray]]
SingleKernel = Callable[[Sequence[numpy.ndarray], Sequence[float]], list[numpy.ndarray]]
FLOAT64 = numpy.dtype(numpy.float64)


def vector_input(value: Any, size: int, name: str, function: str) -> numpy.ndarray:
    """``value`` as a float64 array of shape (..., size), or the numpy backend's error."""
    array = numpy.asarray(value, dtype=numpy.float64)
    if array.ndim == 0 or array.shape[-1] != size:
        raise ValueError(f"{function}(): '{name}' must have shape (..., {size}), got {array.shape}")
    return array


def batch_shape(function: str, *shapes: tuple[int, ...]) -> tuple[int, ...]:
    """Broadcast batch shape of the inputs (numpy's rules), or the numpy backend's error.

    Written out instead of ``numpy.broadcast_shapes``, which costs microseconds per call.
    """
    ndim = max(map(len, shapes), default=0)
    result = [1] * ndim
    for shape in shapes:
        offset = ndim - len(shape)
        for k, size in enumerate(shape):
            current = result[offset + k]
            if size != current:
                if current == 1:
                    result[offset + k] = size
                elif size != 1:
                    raise ValueError(f"{function}(): the batch shapes of the inputs do not broadcast: {shapes}")
    return tuple(result)


def _identifier(name: str) -> str:
    if not name.isidentifier() or keyword.iskeyword(name) or name.startswith("_"):
        raise GeneratedCodeError(f"the manifest names an input {name!r}, which is no valid argument name")
    return name


def _docstring(record: Function, backend: str) -> str:
    lines = [record.summary, "", f"Evaluated by the {backend} backend; any leading batch shape.", "", "Args:"]
    for i in record.inputs:
        if i.is_parameter:
            unit = f" [{i.units[0]}]" if i.units[0] else ""
            lines.append(f"    {i.name}: {i.doc or 'parameter'}{unit}; default {i.default!r}; "
                         "a scalar or an array broadcastable to the batch shape.")
        else:
            elements = ", ".join(f"{n} [{u}]" for n, u in zip(i.elements, i.units))
            lines.append(f"    {i.name}: {i.doc}, shape (..., {i.size}): {elements}.")
    lines += ["", "Returns:"]
    if len(record.results) > 1:
        lines.append(f"    {type_name(record.name)} with the fields:")
    for o in record.results:
        unit = f" [{o.unit}]" if o.unit else ""
        lines.append(f"    {o.name}: shape {shape_text(o.shape)}; {o.doc}{unit}.")
    return "\n".join(lines)


def signature_text(record: Function) -> str:
    """The parameter list of the generated function ``record``: ``q, qd, *, l1=0.1, l2=0.1``."""
    vectors = [_identifier(i.name) for i in record.vector_inputs]
    params = [f"{_identifier(i.name)}={i.default!r}" for i in record.parameter_inputs]
    return ", ".join(vectors + (["*"] if params else []) + params)


def wrap_function(record: Function, kernel: Kernel, backend: str,
                  single: SingleKernel | None = None) -> Callable[..., Any]:
    """The Python function of the manifest function ``record`` evaluated by ``kernel``.

    Args:
        record: the function as the manifest records it.
        kernel: evaluates any batch (see the module docstring).
        backend: backend name, for docstrings and code object names.
        single: optional faster path for the common call of a control loop, used when every
            vector argument is a float64 ndarray of exactly its shape (n,) and every
            parameter a Python float or int: ``single(vectors, params) -> outputs``.

    Raises:
        GeneratedCodeError: the manifest record has an input name that is no identifier.
    """
    name = _identifier(record.name)
    vectors = [(_identifier(i.name), i.size) for i in record.vector_inputs]
    params = [(_identifier(i.name), i.default) for i in record.parameter_inputs]
    outputs = [o.name for o in record.results]
    result_type: Callable[..., Any] | None = (
        collections.namedtuple(type_name(name), outputs) if len(outputs) > 1 else None)

    def evaluate_single(vector_values: Sequence[Any], param_values: Sequence[Any]) -> Any:
        results = single(vector_values, param_values)  # type: ignore[misc]
        return result_type(*results) if result_type is not None else results[0]

    def evaluate(vector_values: Sequence[Any], param_values: Sequence[Any]) -> Any:
        arrays = [vector_input(value, size, vname, name) for value, (vname, size) in zip(vector_values, vectors)]
        param_arrays = [numpy.asarray(value, dtype=numpy.float64) for value in param_values]
        batch = batch_shape(name, *[a.shape[:-1] for a in arrays], *[p.shape for p in param_arrays])
        results = kernel(batch, arrays, param_arrays)
        return result_type(*results) if result_type is not None else results[0]

    signature = signature_text(record)
    arguments = f"({''.join(v + ', ' for v, _ in vectors)}), ({''.join(p + ', ' for p, _ in params)})"
    source = f"def {name}({signature}):\n"
    if single is not None:
        # the checks of the single-configuration path, written out (no loops, no generators)
        checks = [f"type({v}) is _ndarray and {v}.shape == ({size},) and {v}.dtype is _float64" for v, size in vectors]
        checks += [f"(type({p}) is float or type({p}) is int)" for p, _ in params]
        source += f"    if {' and '.join(checks)}:\n        return _evaluate_single({arguments})\n"
    source += f"    return _evaluate({arguments})\n"
    namespace: dict[str, Any] = {"_evaluate": evaluate, "_evaluate_single": evaluate_single,
                                 "_ndarray": numpy.ndarray, "_float64": FLOAT64,
                                 "inf": float("inf"), "nan": float("nan")}
    exec(compile(source, f"<symkin {backend} {name}>", "exec"), namespace)  # noqa: S102 (identifiers checked)
    function = namespace[name]
    function.__doc__ = _docstring(record, backend)
    function.__qualname__ = name
    function.__module__ = f"symkin.generated.{backend}"
    if result_type is not None:
        function.result_type = result_type
    return function

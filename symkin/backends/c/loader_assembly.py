"""The generated assembly's functions of a compiled model library, bound once per library (issue 63).

:class:`AssemblyBinding` holds ``<model>_assemble``, ``<model>_assembly_jacobian`` (and their ``_batch``),
``<model>_actuated_dynamics`` and ``<model>_assemble_inverse_batch`` of a library with their ctypes signatures, and the
compiled CPython entry points over the first two and the dynamics
(:func:`symkin.backends.c.loader_entry_points.assembly_entry_points`).  The C loader binds it while the model's source
and header are at hand (:func:`symkin.backends.c.loader.load`): a model file an analysis derives on the fly loads from
a scratch folder that is gone when the analysis asks for the assembly.  :class:`symkin.runtime.assembly.GeneratedAssembly`
adds a design's parameter values.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Any

from symkin.backends.c.loader_entry_points import assembly_entry_points
from symkin.runtime.info import ModelInfo

#: The generated functions the assembly is made of.
ASSEMBLY_FUNCTIONS = ("closure", "closure_jacobians")
#: The generated function whose projection onto the actuated coordinates ``<model>_actuated_dynamics`` is.
DYNAMICS_FUNCTION = "closure_dynamics"


def _parameter_names(info: ModelInfo, functions: tuple[str, ...]) -> list[str]:
    """The free parameters of ``functions``, the first's, then each next one's others: the order in which
    :func:`symkin.backends.c.assembly.assembly_context` gives them to the assembly's C functions."""
    names: list[str] = []
    for function in functions:
        names += [i.name for i in info.functions[function].inputs if i.is_parameter and i.name not in names]
    return names


def assembly_parameter_names(info: ModelInfo) -> list[str]:
    """The free parameters the generated assembly takes, in its header's order: closure's, then closure_jacobians'
    others."""
    return _parameter_names(info, ASSEMBLY_FUNCTIONS)


def dynamics_parameter_names(info: ModelInfo) -> list[str]:
    """The free parameters ``<model>_actuated_dynamics`` takes, in its header's order: closure_jacobians', then
    closure_dynamics' others."""
    return _parameter_names(info, ("closure_jacobians", DYNAMICS_FUNCTION))


def closure_vector_sizes(info: ModelInfo) -> dict[str, int]:
    """The sizes of the closure's vectors q, s and p (n, ns, np) of the model ``info``, by name."""
    return {v.name: int(v.shape[0]) for v in info.functions["closure"].inputs[:3]}


def _optional(library: ctypes.CDLL, symbol: str, argtypes: list[Any], restype: Any) -> Any:
    """The function ``symbol`` of ``library`` with its ctypes signature, or None where the library lacks it (C code
    derived before it was generated)."""
    try:
        function = library[symbol]
    except AttributeError:
        return None
    function.argtypes, function.restype = argtypes, restype
    return function


class AssemblyBinding:
    """The assembly functions of the compiled ``library`` (at ``path``, its header ``header``) of the model ``info``,
    whose ``<model>_assemble`` is ``assemble`` (:func:`bind_assembly`)."""

    def __init__(self, library: ctypes.CDLL, path: Path, header: Path, info: ModelInfo, assemble: Any):
        name = info.name
        self.assemble = assemble
        self.parameter_names = assembly_parameter_names(info)
        #: the closure's sizes n, ns and np (keys q, s, p)
        self.sizes = closure_vector_sizes(info)
        doubles = [ctypes.c_double] * len(self.parameter_names)
        self.assemble.argtypes = [ctypes.c_void_p] * 3 + doubles + [ctypes.c_int, ctypes.c_double, ctypes.c_void_p]
        self.assemble.restype = ctypes.c_int
        self.jacobian = library[f"{name}_assembly_jacobian"]
        self.jacobian.argtypes = [ctypes.c_void_p] * 3 + doubles + [ctypes.c_void_p]
        self.jacobian.restype = ctypes.c_int
        #: the batches, the inverse's batch (the continuation's) and the dynamics in the actuated coordinates (where the
        #: model has closure_dynamics in C): None where the code predates them
        self.assemble_batch = _optional(library, f"{name}_assemble_batch", [ctypes.c_size_t] + [ctypes.c_void_p] * 3
                                        + doubles + [ctypes.c_int, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p],
                                        None)
        self.jacobian_batch = _optional(library, f"{name}_assembly_jacobian_batch",
                                        [ctypes.c_size_t] + [ctypes.c_void_p] * 3 + doubles + [ctypes.c_void_p] * 2, None)
        self.inverse = _optional(library, f"{name}_assemble_inverse_batch", [ctypes.c_size_t] + [ctypes.c_void_p] * 3
                                 + doubles + [ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                                              ctypes.c_void_p, ctypes.c_void_p], None)
        #: the free parameters of the dynamics, in its order
        self.dynamics_parameter_names = dynamics_parameter_names(info) if DYNAMICS_FUNCTION in info.functions else []
        self.dynamics = None if DYNAMICS_FUNCTION not in info.functions else _optional(
            library, f"{name}_actuated_dynamics",
            [ctypes.c_void_p] * 4 + [ctypes.c_double] * len(self.dynamics_parameter_names) + [ctypes.c_void_p] * 5,
            ctypes.c_int)
        #: the compiled CPython entry points (None: ctypes only); they take exact arrays, the rest goes to ctypes
        self.entry = assembly_entry_points(path, header, name, self.sizes, self.parameter_names,
                                           self.dynamics_parameter_names if self.dynamics is not None else None)


def bind_assembly(library: ctypes.CDLL, path: Path, header: Path, info: ModelInfo) -> AssemblyBinding | None:
    """The assembly functions of the compiled ``library`` (at ``path``, its header ``header``) of the model ``info``,
    or None where it has none (no ``closure`` and ``closure_jacobians``, or C code derived before the generated
    assembly)."""
    if not set(ASSEMBLY_FUNCTIONS) <= set(info.functions):
        return None
    try:
        assemble = library[f"{info.name}_assemble"]
    except AttributeError:
        return None
    return AssemblyBinding(library, path, header, info, assemble)


class CompiledFunctions(dict):
    """The bound functions of a compiled model library (name -> function), and its assembly's binding where the
    model has one (:class:`AssemblyBinding`, else None)."""

    assembly: AssemblyBinding | None = None

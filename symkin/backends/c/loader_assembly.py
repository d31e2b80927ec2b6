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


def assembly_parameter_names(info: ModelInfo) -> list[str]:
    """The free parameters the generated assembly takes, in its header's order: closure's, then closure_jacobians'
    others (:func:`symkin.backends.c.assembly.assembly_context` orders them so from the same functions)."""
    names: list[str] = []
    for function in ASSEMBLY_FUNCTIONS:
        names += [i.name for i in info.functions[function].inputs if i.is_parameter and i.name not in names]
    return names


def dynamics_parameter_names(info: ModelInfo) -> list[str]:
    """The free parameters ``<model>_actuated_dynamics`` takes, in its header's order: closure_jacobians', then
    closure_dynamics' others (:func:`symkin.backends.c.assembly.assembly_context`)."""
    names: list[str] = []
    for function in ("closure_jacobians", DYNAMICS_FUNCTION):
        names += [i.name for i in info.functions[function].inputs if i.is_parameter and i.name not in names]
    return names


class AssemblyBinding:
    """The assembly functions of the compiled ``library`` (at ``path``, its header ``header``) of the model ``info``,
    whose ``<model>_assemble`` is ``assemble`` (:func:`bind_assembly`)."""

    def __init__(self, library: ctypes.CDLL, path: Path, header: Path, info: ModelInfo, assemble: Any):
        name = info.name
        self.assemble = assemble
        self.parameter_names = assembly_parameter_names(info)
        inputs = info.functions["closure"].inputs
        #: the closure's sizes n, ns and np (keys q, s, p)
        self.sizes = {v.name: int(v.shape[0]) for v in inputs[:3]}
        #: ``<model>_actuated_dynamics`` (None: the model has no closure_dynamics in C, or its code predates it)
        self.dynamics: Any = None
        #: its free parameters, in its order
        self.dynamics_parameter_names: list[str] = []
        if DYNAMICS_FUNCTION in info.functions:
            try:
                self.dynamics = library[f"{name}_actuated_dynamics"]
            except AttributeError:
                pass
            else:
                self.dynamics_parameter_names = dynamics_parameter_names(info)
                self.dynamics.argtypes = [ctypes.c_void_p] * 4 + [ctypes.c_double] * len(
                    self.dynamics_parameter_names) + [ctypes.c_void_p] * 5
                self.dynamics.restype = ctypes.c_int
        #: the compiled CPython entry points (None: ctypes only); they take exact arrays, the rest goes to ctypes
        self.entry = assembly_entry_points(path, header, name, self.sizes, self.parameter_names,
                                           self.dynamics_parameter_names if self.dynamics is not None else None)
        doubles = [ctypes.c_double] * len(self.parameter_names)
        self.assemble.argtypes = [ctypes.c_void_p] * 3 + doubles + [ctypes.c_int, ctypes.c_double, ctypes.c_void_p]
        self.assemble.restype = ctypes.c_int
        self.jacobian = library[f"{name}_assembly_jacobian"]
        self.jacobian.argtypes = [ctypes.c_void_p] * 3 + doubles + [ctypes.c_void_p]
        self.jacobian.restype = ctypes.c_int
        self.assemble_batch: Any = None
        self.jacobian_batch: Any = None
        try:    # code derived before the batched assembly has none
            self.assemble_batch, self.jacobian_batch = (library[f"{name}_assemble_batch"],
                                                        library[f"{name}_assembly_jacobian_batch"])
        except AttributeError:
            pass
        else:
            self.assemble_batch.argtypes = [ctypes.c_size_t] + [ctypes.c_void_p] * 3 + doubles + [
                ctypes.c_int, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p]
            self.assemble_batch.restype = None
            self.jacobian_batch.argtypes = [ctypes.c_size_t] + [ctypes.c_void_p] * 3 + doubles + [ctypes.c_void_p] * 2
            self.jacobian_batch.restype = None
        self.inverse: Any
        try:    # code derived before the inverse has none: the continuation then takes the run-time solver
            self.inverse = library[f"{name}_assemble_inverse_batch"]
        except AttributeError:
            self.inverse = None
        else:
            self.inverse.argtypes = [ctypes.c_size_t] + [ctypes.c_void_p] * 3 + doubles + [
                ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
            self.inverse.restype = None


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

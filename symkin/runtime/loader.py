"""Load the generated functions of a model directory written by ``symkin derive``.

This module imports neither sympy nor jinja2: a control loop that only evaluates
generated code pays for numpy (and the backend it picks) alone.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, overload

from symkin.backends import BACKENDS
from symkin.errors import GeneratedCodeError
from symkin.manifest import MANIFEST_NAME, read_manifest
from symkin.runtime.info import ModelInfo


class LoadedModel:
    """The generated functions of one model, as attributes (``ur.fk(q)``, ``ur.jacobian(q)``).

    Attributes:
        name: model name.
        backend: the backend the functions come from.
        directory: the model directory.
        manifest: the parsed ``manifest.json``.
        info: the typed view of the model (:class:`~symkin.runtime.info.ModelInfo`): what consumers read.
        functions: names of the generated functions.
        parameters: default values of the free parameters (inputs of the functions).
    """

    def __init__(self, directory: Path, manifest: dict[str, Any], backend: str,
                 functions: dict[str, Callable[..., Any]], bound: dict[str, float] | None = None,
                 info: ModelInfo | None = None):
        self.directory = directory
        self.manifest = manifest
        self.backend = backend
        self.info = ModelInfo.from_manifest(manifest) if info is None else info
        self.name: str = self.info.name
        self._raw = functions
        self._bound = dict(bound or {})
        self.functions = tuple(functions)
        self.parameters = {p.name: p.default for p in self.info.parameters if not p.fixed}
        self.parameters.update(self._bound)
        for name, fn in functions.items():
            bound_here = {k: v for k, v in self._bound.items() if k in self.info.functions[name].parameters}
            setattr(self, name, functools.partial(fn, **bound_here) if bound_here else fn)

    @property
    def joint_limits(self) -> tuple[tuple[float, float], ...]:
        """(lower, upper) position limit of every joint, at the parameters' default values;
        (-inf, inf) for a joint without limits."""
        return tuple(c.bounds for c in self.info.coordinates)

    @property
    def assembly_binding(self) -> Any:
        """The generated assembly's functions of a model loaded with the C backend, bound when it was loaded
        (:class:`symkin.backends.c.loader_assembly.AssemblyBinding`), else None."""
        return getattr(self._raw, "assembly", None)

    def __getattr__(self, name: str) -> Any:
        """Only for names that are not attributes: the generated functions are set in __init__."""
        model = self.__dict__.get("name", "this model")
        raise AttributeError(f"{model} has no generated function or attribute {name!r} "
                             f"(generated: {', '.join(self.__dict__.get('functions', ()))})")

    def bind(self, **parameters: float) -> LoadedModel:
        """A view whose functions use these parameter values instead of the defaults.

        Each function receives only the parameters it depends on, so one call binds a
        design (e.g. ``arm.bind(l1=0.2, l2=0.2)``) for every function.

        Raises:
            KeyError: a name is not a free parameter of the model.
        """
        unknown = set(parameters) - set(self.parameters)
        if unknown:
            raise KeyError(f"{self.name}: not free parameters: {sorted(unknown)}; free: {sorted(self.parameters)}")
        return type(self)(self.directory, self.manifest, self.backend, self._raw, {**self._bound, **parameters},
                          self.info)

    def unbound(self, name: str) -> tuple[Callable[..., Any], dict[str, float]]:
        """The generated function ``name`` without this view's parameter values, and the values of the free
        parameters it takes (the defaults and those bound), as floats: for code that passes them as arguments, e.g.
        a JAX function compiled once for every design of a sweep (its parameters traced)."""
        takes = self.info.functions[name].parameters
        return self._raw[name], {k: float(v) for k, v in self.parameters.items() if k in takes}

    def __repr__(self) -> str:
        return f"<symkin model {self.name!r} ({self.backend}): {', '.join(self.functions)}>"


ModelT = TypeVar("ModelT", bound=LoadedModel)


@overload
def load(path: str | Path, backend: str = "numpy") -> LoadedModel: ...


@overload
def load(path: str | Path, backend: str = "numpy", *, model_class: type[ModelT]) -> ModelT: ...


def load(path: str | Path, backend: str = "numpy", *, model_class: type[LoadedModel] = LoadedModel) -> LoadedModel:
    """Load the generated code of a model.

    Args:
        path: the model directory written by ``symkin derive`` (``OUT/<model>``) or its
            ``manifest.json``.
        backend: which emitted backend to use (``numpy`` by default).
        model_class: the class of the result, LoadedModel or a subclass (``symkin.load`` gives
            :class:`symkin.viewer.notebook.NotebookModel`, which notebooks show as the 3D viewer).

    Raises:
        GeneratedCodeError: no manifest, or the backend was not emitted for this model.
    """
    directory = Path(path)
    if directory.name == MANIFEST_NAME:
        directory = directory.parent
    manifest = read_manifest(directory)
    info = ModelInfo.from_manifest(manifest)  # once: the loaders and the model read it
    emitted = info.backend_files
    if backend not in emitted:
        raise GeneratedCodeError(f"{directory}: no '{backend}' code was emitted (emitted: {', '.join(emitted)}); "
                                 f"derive again with --backend {backend}")
    loaders = {name: b.loader for name, b in BACKENDS.items() if b.loader is not None}
    if backend not in loaders:
        raise GeneratedCodeError(f"this symkin cannot load '{backend}' code (known: {', '.join(loaders)})")
    # the backend names its loader, a module of the runtime layer (casadi, a compiler), imported only now
    functions = importlib.import_module(loaders[backend]).load(directory, info)
    return model_class(directory, manifest, backend, functions, info=info)

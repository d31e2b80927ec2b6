"""A lazy, memoized graph of named symbolic quantities.

Quantities (``fk``, ``jacobian``, later ``mass_matrix``...) are registered with the
:func:`quantity` decorator by the modules that know how to derive them.  A
:class:`Derivation` computes a quantity the first time it is asked for, together with
exactly what it depends on, and remembers it: no call-order rules, nothing derived twice,
nothing derived that was not needed (asking for ``fk`` never derives a Jacobian).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from symkin.errors import DerivationError
from symkin.ir.spec import FunctionSpec
from symkin.model.schema import Model


@dataclass(frozen=True)
class QuantityDef:
    """A registered quantity.

    Attributes:
        name: key in the graph (and name of the generated function when emitted).
        summary: one line shown by ``symkin quantities`` and in docs.
        compute: ``compute(derivation) -> value``; asks the derivation for what it needs.
        emitted: True if the value is a :class:`FunctionSpec` that backends turn into code.
        solves_with: the emitted quantity whose (square) matrix this one inverts, e.g.
            ``mass_matrix`` for forward dynamics; its condition number bounds the accuracy any
            algorithm can reach (used by the stability analysis).  None if nothing is inverted.
    """

    name: str
    summary: str
    compute: Callable[["Derivation"], Any]
    emitted: bool
    solves_with: str | None = None


_REGISTRY: dict[str, QuantityDef] = {}


def quantity(name: str, summary: str, emitted: bool = True,
             solves_with: str | None = None) -> Callable[[Callable[["Derivation"], Any]], Callable[["Derivation"], Any]]:
    """Register ``compute`` as the derivation of quantity ``name`` (see :class:`QuantityDef`)."""

    def register(compute: Callable[["Derivation"], Any]) -> Callable[["Derivation"], Any]:
        if name in _REGISTRY:
            raise ValueError(f"quantity {name!r} registered twice")
        _REGISTRY[name] = QuantityDef(name, summary, compute, emitted, solves_with)
        return compute

    return register


def registry() -> dict[str, QuantityDef]:
    """All registered quantities by name (a copy)."""
    return dict(_REGISTRY)


def emitted_quantities() -> tuple[str, ...]:
    """Names of the quantities that can be requested as generated functions."""
    return tuple(name for name, q in _REGISTRY.items() if q.emitted)


class Derivation:
    """The derivation graph of one model.

    Attributes:
        model: the model.
        computed: names of the quantities derived so far, in completion order.
        seconds: time spent in each quantity, excluding its dependencies.
    """

    def __init__(self, model: Model):
        self.model = model
        self._values: dict[str, Any] = {}
        self._active: list[str] = []
        self.computed: list[str] = []
        self.seconds: dict[str, float] = {}

    def __getitem__(self, name: str) -> Any:
        if name in self._values:
            return self._values[name]
        if name not in _REGISTRY:
            raise DerivationError(f"unknown quantity {name!r}; known: {', '.join(sorted(_REGISTRY))}")
        if name in self._active:
            raise DerivationError(f"quantity dependency cycle: {' -> '.join(self._active + [name])}")
        self._active.append(name)
        start = time.perf_counter()
        children_before = sum(self.seconds.values())
        try:
            value = _REGISTRY[name].compute(self)
        finally:
            self._active.pop()
        elapsed = time.perf_counter() - start
        self.seconds[name] = elapsed - (sum(self.seconds.values()) - children_before)
        self._values[name] = value
        self.computed.append(name)
        return value

    def functions(self, names: Iterable[str]) -> list[FunctionSpec]:
        """The function specs of the requested emitted quantities, in request order."""
        specs = []
        for name in names:
            if name not in _REGISTRY or not _REGISTRY[name].emitted:
                raise DerivationError(f"{name!r} is not an output; outputs: {', '.join(emitted_quantities())}")
            spec = self[name]
            if not isinstance(spec, FunctionSpec):
                raise DerivationError(f"quantity {name!r} did not produce a function spec")
            specs.append(spec)
        return specs

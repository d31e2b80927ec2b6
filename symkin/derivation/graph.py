"""A lazy, memoized graph of named symbolic quantities.

Quantities (``fk``, ``jacobian``, later ``mass_matrix``...) are registered with the
:func:`quantity` decorator by the modules that know how to derive them.  A
:class:`Derivation` computes a quantity the first time it is asked for, together with
exactly what it depends on, and remembers it: no call-order rules, nothing derived twice,
nothing derived that was not needed (asking for ``fk`` never derives a Jacobian).

A quantity belongs to serial chains (the default), to parallel mechanisms, or to ``any``
model; one name may have a serial and a parallel derivation (``fk``, ``jacobian``), and
asking a model for a quantity of the other kind is a clear :class:`DerivationError`.
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
        mechanism: ``serial``, ``parallel`` or ``any``: the models it is derived for.
        residual: True if the value vanishes wherever the mechanism is assembled (loop-closure
            and leg equations): its accuracy is judged away from that manifold, where a
            relative error means something (used by the stability analysis).
    """

    name: str
    summary: str
    compute: Callable[["Derivation"], Any]
    emitted: bool
    solves_with: str | None = None
    mechanism: str = "serial"
    residual: bool = False


MECHANISMS = ("serial", "parallel", "any")

#: name -> mechanism -> definition
_REGISTRY: dict[str, dict[str, QuantityDef]] = {}


def quantity(name: str, summary: str, emitted: bool = True, solves_with: str | None = None,
             mechanism: str = "serial", residual: bool = False) -> Callable[[Callable[["Derivation"], Any]], Callable[["Derivation"], Any]]:
    """Register ``compute`` as the derivation of quantity ``name`` for ``mechanism`` models (see :class:`QuantityDef`)."""
    if mechanism not in MECHANISMS:
        raise ValueError(f"mechanism must be one of {MECHANISMS}, got {mechanism!r}")

    def register(compute: Callable[["Derivation"], Any]) -> Callable[["Derivation"], Any]:
        defs = _REGISTRY.setdefault(name, {})
        if mechanism in defs or "any" in defs or (mechanism == "any" and defs):
            raise ValueError(f"quantity {name!r} registered twice")
        defs[mechanism] = QuantityDef(name, summary, compute, emitted, solves_with, mechanism, residual)
        return compute

    return register


def _definition(name: str, mechanism: str) -> QuantityDef | None:
    defs = _REGISTRY.get(name, {})
    return defs.get(mechanism) or defs.get("any")


def registry(mechanism: str = "serial") -> dict[str, QuantityDef]:
    """The quantities derivable for ``mechanism`` models, by name (a copy)."""
    return {name: d for name in _REGISTRY if (d := _definition(name, mechanism)) is not None}


def emitted_quantities(mechanism: str | None = None) -> tuple[str, ...]:
    """Names of the quantities that can be requested as generated functions (for one kind of model, or any)."""
    kinds = MECHANISMS if mechanism is None else (mechanism,)
    return tuple(name for name, defs in _REGISTRY.items()
                 if any((d := _definition(name, kind)) is not None and d.emitted for kind in kinds))


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

    def _definition(self, name: str) -> QuantityDef:
        if name not in _REGISTRY:
            raise DerivationError(f"unknown quantity {name!r}; known: {', '.join(sorted(_REGISTRY))}")
        definition = _definition(name, self.model.mechanism)
        if definition is None:
            other = " or ".join(sorted(_REGISTRY[name]))
            raise DerivationError(
                f"{name!r} is derived for {other} mechanisms, but model '{self.model.name}' is a "
                f"{self.model.mechanism} mechanism; its outputs are: {', '.join(emitted_quantities(self.model.mechanism))}")
        return definition

    def __getitem__(self, name: str) -> Any:
        if name in self._values:
            return self._values[name]
        definition = self._definition(name)
        if name in self._active:
            raise DerivationError(f"quantity dependency cycle: {' -> '.join(self._active + [name])}")
        self._active.append(name)
        start = time.perf_counter()
        children_before = sum(self.seconds.values())
        try:
            value = definition.compute(self)
        finally:
            self._active.pop()
        elapsed = time.perf_counter() - start
        self.seconds[name] = elapsed - (sum(self.seconds.values()) - children_before)
        self._values[name] = value
        self.computed.append(name)
        return value

    def available(self, names: Iterable[str]) -> tuple[list[str], dict[str, str]]:
        """(the quantities of ``names`` this model can derive, {skipped name: reason}).

        Deriving is how a quantity finds out whether the model has what it needs (no
        ``gravity_vector`` without gravity, no dynamics without bodies), so the kept ones
        are derived (and memoized) on the way.
        """
        kept, skipped = [], {}
        for name in names:
            try:
                self[name]
            except DerivationError as err:
                skipped[name] = str(err)
                continue
            kept.append(name)
        return kept, skipped

    def functions(self, names: Iterable[str]) -> list[FunctionSpec]:
        """The function specs of the requested emitted quantities, in request order."""
        specs = []
        for name in names:
            if name not in _REGISTRY or not self._definition(name).emitted:
                outputs = ", ".join(emitted_quantities(self.model.mechanism))
                raise DerivationError(f"{name!r} is not an output; outputs: {outputs}")
            spec = self[name]
            if not isinstance(spec, FunctionSpec):
                raise DerivationError(f"quantity {name!r} did not produce a function spec")
            specs.append(spec)
        return specs

"""A lazy, memoized graph of named symbolic quantities.

Quantities (``fk``, ``jacobian``, ``mass_matrix``...) are defined by the modules listed in
:data:`symkin.derivation.catalog.QUANTITY_MODULES`.  A
:class:`Derivation` computes a quantity the first time it is asked for, together with
exactly what it depends on, and remembers it: no call-order rules, nothing derived twice,
nothing derived that was not needed (asking for ``fk`` never derives a Jacobian).

A quantity belongs to serial chains (the default), to parallel mechanisms, or to ``any``
model; one name may have a serial and a parallel derivation (``fk``, ``jacobian``), and
asking a model for a quantity of the other kind is a clear :class:`DerivationError`.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

from symkin.derivation import catalog
from symkin.errors import DerivationError
from symkin.ir.quantity import QuantityDef, QuantityKey, definition_of
from symkin.ir.spec import FunctionSpec
from symkin.model.schema import Model


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

    def of(self, model: Model) -> Derivation:
        """A new graph for a model built from this one (a hybrid device's serial chain,
        :mod:`symkin.parallel.hybrid`): quantities ask for it through a memoized quantity of their own."""
        return Derivation(model)

    def _definition(self, name: str) -> QuantityDef:
        if name not in catalog.QUANTITIES:
            raise DerivationError(f"unknown quantity {name!r}; known: {', '.join(sorted(catalog.QUANTITIES))}")
        definition = catalog.definition(name, self.model.mechanism)
        if definition is None:
            other = " or ".join(sorted(catalog.QUANTITIES[name]))
            outputs = ", ".join(catalog.emitted_quantities(self.model.mechanism))
            raise DerivationError(
                f"{name!r} is derived for {other} mechanisms, but model '{self.model.name}' is a "
                f"{self.model.mechanism} mechanism; its outputs are: {outputs}")
        return definition

    def _resolve(self, key: QuantityKey) -> QuantityDef:
        """The definition of ``key``: a marked function's own, or the catalog's for a name."""
        if isinstance(key, str):
            return self._definition(key)
        definition = definition_of(key)
        if definition is None:
            raise DerivationError(f"{key!r} is neither a quantity name nor a function marked with @quantity")
        if definition.mechanism not in (self.model.mechanism, "any"):
            raise DerivationError(f"{definition.name!r} ({key.__module__}) is derived for {definition.mechanism} "
                                  f"mechanisms, but model '{self.model.name}' is a {self.model.mechanism} mechanism")
        return definition

    def __getitem__(self, key: QuantityKey) -> Any:
        """The value of a quantity, asked for by name or by its marked function (see :data:`QuantityKey`)."""
        definition = self._resolve(key)
        name = definition.name
        if name in self._values:
            return self._values[name]
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
            if name not in catalog.QUANTITIES or not self._definition(name).emitted:
                outputs = ", ".join(catalog.emitted_quantities(self.model.mechanism))
                raise DerivationError(f"{name!r} is not an output; outputs: {outputs}")
            spec = self[name]
            if not isinstance(spec, FunctionSpec):
                raise DerivationError(f"quantity {name!r} did not produce a function spec")
            specs.append(spec)
        return specs

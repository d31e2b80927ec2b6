"""What a derivable quantity is: a name, how it is computed, and what it means.

The modules that know how to derive quantities (``symkin.kinematics.quantities``,
``symkin.dynamics.quantities``, ``symkin.parallel.quantities``) mark their functions with
:func:`quantity`; nothing is registered by importing them.  The list of those modules is
explicit, in :data:`symkin.derivation.catalog.QUANTITY_MODULES`, like the list of
optimization passes, and :class:`symkin.derivation.graph.Derivation` computes what they define.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from symkin.model.schema import Model

MECHANISMS = ("serial", "parallel", "any")

#: What a derivation is asked for.  Inside symkin, a quantity asks for another by the marked
#: function itself (``d[chain_frames]``): a misspelt key is a NameError at import, and the
#: definition used is the one named, never looked up.  Names (``d["fk"]``) are for the
#: boundary, where they come from a model file, a command line or a test, and are validated.
QuantityKey = str | Callable[..., Any]


class Deriving(Protocol):
    """What a quantity's compute function is given: the model, any other quantity by its key, and the derivation
    of another model (a hybrid device's wrist).  :class:`symkin.derivation.graph.Derivation` is one; the quantity
    modules type against this protocol, so that nothing below the derivation graph names it."""

    model: Model

    def __getitem__(self, key: QuantityKey) -> Any: ...

    def of(self, model: Model) -> Deriving: ...


@dataclass(frozen=True)
class QuantityDef:
    """A quantity's definition.

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
        kappa_degree: the degree of the value in the matrix that conditions it: a quadratic
            form such as J^-T M J^-1 doubles that matrix's relative error (its relative condition
            number is 2), so the stability analysis judges it by kappa_degree * kappa.
    """

    name: str
    summary: str
    compute: Callable[[Deriving], Any]
    emitted: bool
    solves_with: str | None = None
    mechanism: str = "serial"
    residual: bool = False
    kappa_degree: int = 1


def definition_of(key: QuantityKey) -> QuantityDef | None:
    """The definition a marked function carries; None for a name, or for an unmarked function."""
    definition = getattr(key, "quantity", None) if callable(key) else None
    return definition if isinstance(definition, QuantityDef) else None


def quantity(name: str, summary: str, emitted: bool = True, solves_with: str | None = None,
             mechanism: str = "serial", residual: bool = False, kappa_degree: int = 1
             ) -> Callable[[Callable[[Deriving], Any]], Callable[[Deriving], Any]]:
    """Mark ``compute`` as the derivation of quantity ``name`` for ``mechanism`` models (see
    :class:`QuantityDef`); the function keeps working as itself and carries its definition as
    ``compute.quantity``."""
    if mechanism not in MECHANISMS:
        raise ValueError(f"mechanism must be one of {MECHANISMS}, got {mechanism!r}")

    def mark(compute: Callable[[Deriving], Any]) -> Callable[[Deriving], Any]:
        setattr(compute, "quantity", QuantityDef(name, summary, compute, emitted, solves_with, mechanism, residual,
                                                 kappa_degree))
        return compute

    return mark

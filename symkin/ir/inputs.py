"""Vector inputs of generated functions (``q``, ``qd``, ``qdd``, ``tau``), shared by all quantities."""

from __future__ import annotations

from symkin.ir.spec import InputSpec
from symkin.model import coordinates
from symkin.model.schema import Model


def coordinate_input(model: Model, group: str) -> InputSpec:
    """The vector input of a coordinate group of ``model`` (see :mod:`symkin.model.coordinates`)."""
    return InputSpec(
        name=group,
        kind="vector",
        symbols=coordinates.symbols(model, group),
        element_names=tuple(j.name for j in model.coordinates),
        units=coordinates.units(model, group),
        doc=coordinates.GROUPS[group].doc,
    )

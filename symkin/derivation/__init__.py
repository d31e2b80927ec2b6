"""Lazy derivation of symbolic quantities (see :mod:`symkin.derivation.graph`).

The quantities symkin knows are those of the modules listed in
:data:`symkin.derivation.catalog.QUANTITY_MODULES`.
"""

from symkin.derivation.catalog import emitted_quantities, registry
from symkin.derivation.graph import Derivation
from symkin.ir.quantity import QuantityDef, quantity

__all__ = ["Derivation", "QuantityDef", "emitted_quantities", "quantity", "registry"]

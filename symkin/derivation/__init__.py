"""Lazy derivation of symbolic quantities (see :mod:`symkin.derivation.graph`).

Importing this package registers every quantity symkin knows.
"""

from symkin.derivation.graph import Derivation, QuantityDef, emitted_quantities, quantity, registry
from symkin.kinematics import quantities as _kinematics  # noqa: F401  (registers fk, frames, jacobian...)
from symkin.dynamics import quantities as _dynamics  # noqa: F401  (registers mass_matrix, inverse_dynamics...)
from symkin.parallel import quantities as _parallel  # noqa: F401  (registers ik, fk, closure... of parallel models)

__all__ = ["Derivation", "QuantityDef", "emitted_quantities", "quantity", "registry"]

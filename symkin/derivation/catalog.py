"""Which quantities symkin can derive: an explicit list of the modules that define them.

Adding a family of quantities (say, the dynamics of parallel mechanisms) is one module whose
functions carry :func:`symkin.ir.quantity.quantity` marks, appended to
:data:`QUANTITY_MODULES`; their order is the order of the quantities everywhere (manifest,
``symkin quantities``, generated files).
"""

from __future__ import annotations

from types import ModuleType

from symkin.dynamics import quantities as dynamics_quantities
from symkin.dynamics import derivatives, joint_forces, regressor
from symkin.ir.quantity import MECHANISMS, QuantityDef
from symkin.kinematics import quantities as kinematics_quantities
from symkin.parallel import base_regressor as parallel_base_regressor
from symkin.parallel import closure_base, closure_dynamics
from symkin.parallel import derivatives as parallel_derivatives
from symkin.parallel import dynamics as parallel_dynamics
from symkin.parallel import forces as parallel_forces
from symkin.parallel import hybrid
from symkin.parallel import quantities as parallel_quantities
from symkin.parallel import regressor as parallel_regressor

QUANTITY_MODULES: tuple[ModuleType, ...] = (kinematics_quantities, joint_forces, dynamics_quantities, derivatives, regressor,
                                            parallel_quantities, parallel_forces, parallel_dynamics, parallel_derivatives,
                                            parallel_regressor, parallel_base_regressor, hybrid, closure_dynamics,
                                            closure_base)


def collect(modules: tuple[ModuleType, ...]) -> dict[str, dict[str, QuantityDef]]:
    """name -> mechanism -> definition, for the marked functions defined in ``modules``, in order.

    Raises:
        ValueError: a quantity is defined twice for the same kind of model.
    """
    table: dict[str, dict[str, QuantityDef]] = {}
    for module in modules:
        for value in vars(module).values():
            definition = getattr(value, "quantity", None)
            if not isinstance(definition, QuantityDef) or value.__module__ != module.__name__:
                continue
            defs = table.setdefault(definition.name, {})
            if definition.mechanism in defs or "any" in defs or (definition.mechanism == "any" and defs):
                raise ValueError(f"quantity {definition.name!r} defined twice ({module.__name__})")
            defs[definition.mechanism] = definition
    return table


#: name -> mechanism -> definition.
QUANTITIES = collect(QUANTITY_MODULES)


def definition(name: str, mechanism: str) -> QuantityDef | None:
    """The definition of ``name`` for ``mechanism`` models (or for any model), None if there is none."""
    defs = QUANTITIES.get(name, {})
    return defs.get(mechanism) or defs.get("any")


def registry(mechanism: str = "serial") -> dict[str, QuantityDef]:
    """The quantities derivable for ``mechanism`` models, by name (a copy)."""
    return {name: d for name in QUANTITIES if (d := definition(name, mechanism)) is not None}


def emitted_quantities(mechanism: str | None = None) -> tuple[str, ...]:
    """Names of the quantities that can be requested as generated functions (for one kind of model, or any)."""
    kinds = MECHANISMS if mechanism is None else (mechanism,)
    return tuple(name for name, defs in QUANTITIES.items()
                 if any((d := definition(name, kind)) is not None and d.emitted for kind in kinds))

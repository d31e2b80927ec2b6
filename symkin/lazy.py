"""Packages whose public names are imported when first used (PEP 562).

A package that re-exports its modules' names eagerly imports all of them with the first of its modules anyone
imports (a command line parser reading one constant pays for CasADi and every analysis).  Such a package lists
its names instead and takes ``__getattr__`` and ``__dir__`` from :func:`lazy_exports`::

    _EXPORTS = {"gci": "global_indices", ...}          # public name -> defining module of the package
    __all__ = sorted(_EXPORTS)
    __getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

A name may also come from a module elsewhere in symkin, given by its full name (``"symkin.numerics.conditioning"``).
A public name must not also be a module of the package: importing that module would bind the package attribute to
the module before the name was asked for.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_exports(package: str, namespace: dict[str, Any], exports: dict[str, str]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """(``__getattr__``, ``__dir__``) of ``package``: a name of ``exports`` is imported from its module on first use
    and kept in the package's ``namespace``."""

    def __getattr__(name: str) -> Any:
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module = exports[name]
        value = getattr(importlib.import_module(module if module.startswith("symkin.") else f"{package}.{module}"),
                        name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__

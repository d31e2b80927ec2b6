"""symkin: exact symbolic kinematics and dynamics of mechanisms, emitted as fast code.

Typical use::

    $ symkin derive models/ur10e.yaml -o generated

    from symkin import load
    ur = load("generated/ur10e")
    T = ur.fk(q)          # (..., 4, 4)
    J = ur.jacobian(q)    # (..., 6, 6)

``load`` needs only numpy; the symbolic side (``load_model``, ``derive``) imports sympy
on first use.  In a notebook, a loaded model shows as the interactive 3D viewer of
``symkin view`` (its ``_repr_html_``, :mod:`symkin.viewer.notebook`).
"""

from __future__ import annotations

from typing import Any

from symkin._version import __version__
from symkin.runtime import LoadedModel
from symkin.viewer.notebook import load

__all__ = ["LoadedModel", "__version__", "derive", "load", "load_model"]


def __getattr__(name: str) -> Any:
    # The symbolic API is imported on demand, so `from symkin import load` stays light.
    if name == "load_model":
        from symkin.model import load_model

        return load_model
    if name == "derive":
        from symkin.api import derive

        return derive
    raise AttributeError(f"module 'symkin' has no attribute {name!r}")

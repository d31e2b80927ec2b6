"""The ``scene:`` section: what ``symkin derive`` emits by default (outputs, fixed parameters, backends)."""

from __future__ import annotations

import difflib
from collections.abc import Callable
from typing import Any

from symkin.model.reader import Reader, describe
from symkin.model.schema import Parameter, Scene
from symkin.model.yaml_source import KeyPath, shorten


def read_scene(r: Reader, value: Any, parameters: tuple[Parameter, ...],
           default_outputs: tuple[str, ...] = ("fk", "jacobian")) -> Scene:
    """The default request; output and backend names are checked by the pipeline, which knows them."""
    path: KeyPath = ("scene",)
    section = r.mapping(path, value, optional=("outputs", "fixed", "backends", "float32", "combine"))
    default = Scene(outputs=default_outputs)
    if section is None:
        return default

    def names(key: str, check: Callable[[KeyPath, str], bool]) -> tuple[str, ...] | None:
        if key not in section:
            return None
        items = r.sequence(path + (key,), section[key], what="names")
        if items is None:
            return None
        out = []
        for i, item in enumerate(items):
            if isinstance(item, str) and item in out:
                r.fail(path + (key, i), f"'{shorten(item)}' appears twice", f"list each of the {key} once")
            elif isinstance(item, str) and check(path + (key, i), item):
                out.append(item)
            elif not isinstance(item, str):
                r.fail(path + (key, i), f"expected a name, got {describe(item)}", "write a name")
        return tuple(out)

    pnames = {p.name for p in parameters}

    def is_parameter(ipath: KeyPath, item: str) -> bool:
        if item in pnames:
            return True
        close = difflib.get_close_matches(item, pnames, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        r.fail(ipath, f"'{shorten(item)}' is not a free parameter of the model", f"{hint}list names declared under 'parameters:'")
        return False

    fixed_value = section.get("fixed")
    if fixed_value == "all":
        fixed: tuple[str, ...] | None = tuple(p.name for p in parameters)
    else:
        fixed = names("fixed", is_parameter)
    outputs = names("outputs", lambda _p, _i: True)
    backends = names("backends", lambda _p, _i: True)
    float32 = section.get("float32", False)
    if not isinstance(float32, bool):
        r.fail(path + ("float32",), f"'float32' must be true or false, got {describe(float32)}",
               "write true or false")
        float32 = False
    combine = None if section.get("combine", "all") == "all" else names("combine", lambda _p, _i: True)
    return Scene(outputs=outputs if outputs is not None else default.outputs,
                 fixed=fixed or (),
                 backends=backends if backends is not None else default.backends,
                 float32=float32,
                 combine=combine)

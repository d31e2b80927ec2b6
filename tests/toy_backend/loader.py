"""Load what the toy backend wrote: import ``<model>_toy.py`` and return its functions as numpy arrays."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def load(directory: Path, info: Any) -> dict[str, Callable[..., Any]]:
    path = Path(directory) / info.backend_files["toy"][0]
    spec = importlib.util.spec_from_file_location(f"toy_{info.name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)

    def arrays(function: Callable[..., Any]) -> Callable[..., Any]:
        def call(*vectors: Any, **parameters: float) -> Any:
            result = function(*(np.asarray(v, dtype=float).tolist() for v in vectors), **parameters)
            values = {name: np.asarray(value, dtype=float) for name, value in result.items()}
            return values if len(values) > 1 else next(iter(values.values()))
        return call

    return {name: arrays(getattr(module, name)) for name in info.functions}

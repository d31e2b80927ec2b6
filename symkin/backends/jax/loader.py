"""Import a model's generated JAX module (no sympy, no jinja2); JAX itself is imported here, when a model's code is
loaded with ``backend="jax"``."""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

from symkin.backends.numpy.loader import import_module
from symkin.errors import GeneratedCodeError
from symkin.runtime.info import ModelInfo


def load(directory: Path, info: ModelInfo) -> dict[str, Callable[..., Any]]:
    """The model's functions from its JAX module (``<model>_jax.py``), imported under a name unique to its bytes.

    Raises:
        GeneratedCodeError: JAX is not installed, or the manifest lists no JAX module.
    """
    if importlib.util.find_spec("jax") is None:
        raise GeneratedCodeError(f"{directory}: the jax backend needs JAX: pip install 'symkin[jax]' (or jax)")
    return import_module(Path(directory), info, "jax")

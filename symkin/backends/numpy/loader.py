"""Import a model's generated numpy module (no sympy, no jinja2: a control loop imports it)."""

from __future__ import annotations

import hashlib
import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import Any

from symkin.errors import GeneratedCodeError
from symkin.runtime.info import ModelInfo


def load(directory: Path, info: ModelInfo) -> dict[str, Callable[..., Any]]:
    """The model's functions from ``<model>.py`` (:func:`import_module`)."""
    return import_module(Path(directory), info, "numpy")


def import_module(directory: Path, info: ModelInfo, backend: str) -> dict[str, Callable[..., Any]]:
    """The model's functions from the Python module ``backend`` wrote (numpy, JAX), imported under a name unique to
    the module's bytes.

    The model hash names the mechanism, not what was emitted from it (two scenes of one model give
    two modules), so the import name is keyed by the file's content.
    """
    files = info.backend_files.get(backend, ())
    if not files:
        raise GeneratedCodeError(f"{directory}: the manifest lists no {backend} module")
    path = Path(directory) / files[0]
    try:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as error:
        raise GeneratedCodeError(f"cannot read the generated module {path}: {error.strerror}") from error
    module_name = f"symkin_generated_{info.name}_{digest[:12]}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise GeneratedCodeError(f"cannot import the generated module {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return {name: getattr(module, name) for name in info.functions}

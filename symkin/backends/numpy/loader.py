"""Import a model's generated numpy module (no sympy, no jinja2: a control loop imports it)."""

from __future__ import annotations

import hashlib
import types
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
    two modules), so the import name is keyed by the file's content.  The module runs the bytes that were read and
    hashed, compiled here: never a ``__pycache__`` file beside it (a generated folder may come from a stranger, and
    Python trusts a cached ``.pyc`` whose recorded source size and mtime match - a planted one, or a stale one when
    a module is rewritten within a second at the same size) and none is written into the folder.
    """
    files = info.backend_files.get(backend, ())
    if not files:
        raise GeneratedCodeError(f"{directory}: the manifest lists no {backend} module")
    path = Path(directory) / files[0]
    try:
        source = path.read_bytes()
    except OSError as error:
        raise GeneratedCodeError(f"cannot read the generated module {path}: {error.strerror}") from error
    module_name = f"symkin_generated_{info.name}_{hashlib.sha256(source).hexdigest()[:12]}"
    module = types.ModuleType(module_name)
    module.__file__ = str(path)
    exec(compile(source, str(path), "exec", dont_inherit=True), module.__dict__)  # noqa: S102 - symkin's own output
    return {name: getattr(module, name) for name in info.functions}

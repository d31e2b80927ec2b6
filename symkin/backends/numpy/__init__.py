"""The numpy backend: one importable, vectorized Python module per model.

Loading generated code must stay cheap (a control loop imports it), so this module imports
neither sympy nor jinja2; the emitter is imported only when code is generated.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symkin.errors import GeneratedCodeError

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class NumpyBackend:
    """Emits ``<model>.py``: vectorized numpy functions with docstrings."""

    name = "numpy"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.numpy.emit import emit_module

        return emit_module(code)

    def load(self, directory: Path, manifest: dict[str, Any]) -> dict[str, Callable[..., Any]]:
        files = manifest.get("backends", {}).get(self.name, {}).get("files", [])
        if not files:
            raise GeneratedCodeError(f"{directory}: the manifest lists no numpy module")
        path = Path(directory) / files[0]
        module_name = f"symkin_generated_{manifest['model']['name']}_{manifest['model']['hash'][7:19]}"
        spec = importlib.util.spec_from_file_location(module_name, path)
        if spec is None or spec.loader is None:
            raise GeneratedCodeError(f"cannot import the generated module {path}")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return {f["name"]: getattr(module, f["name"]) for f in manifest["functions"]}

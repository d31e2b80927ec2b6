"""The generated numpy code of a model as bytes: what a worker on any machine needs to evaluate it.

Dask tasks (design sweeps, chunked integrations) carry a :class:`ModelPayload` (the manifest and
the numpy module, a few tens of kB) instead of a path, so the workers of a cluster need symkin
installed but no shared file system; each worker process writes it once into a scratch
directory and loads it (:meth:`ModelPayload.load`, cached by the files' digest).
"""

from __future__ import annotations

import hashlib
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class ModelPayload:
    """The generated numpy code of a model as bytes: what a worker needs to evaluate designs.

    Attributes:
        name: the model name.
        model_hash: the hash of the model source (manifest ``model.hash``).
        files: (file name, content) of the manifest and the numpy module.
    """

    name: str
    model_hash: str
    files: tuple[tuple[str, bytes], ...]

    @classmethod
    def from_directory(cls, directory: str | Path) -> ModelPayload:
        directory = Path(directory)
        manifest = json.loads((directory / "manifest.json").read_text())
        if "numpy" not in manifest.get("backends", {}):
            raise ValueError(f"{directory}: no numpy code generated (derive with --backend numpy)")
        names = ["manifest.json", *manifest["backends"]["numpy"]["files"]]
        return cls(manifest["model"]["name"], manifest["model"]["hash"],
                   tuple((n, (directory / n).read_bytes()) for n in names))

    @property
    def digest(self) -> str:
        """sha256 of the files: the key of the worker-side cache."""
        h = hashlib.sha256()
        for name, content in self.files:
            h.update(name.encode() + b"\0" + content)
        return h.hexdigest()

    def load(self) -> Any:
        """The loaded numpy model, written once per process into a scratch directory."""
        digest = self.digest
        if digest not in _LOADED:
            from symkin import load

            directory = Path(tempfile.mkdtemp(prefix=f"symkin-sweep-{self.name}-"))
            for name, content in self.files:
                (directory / name).write_bytes(content)
            _LOADED[digest] = load(directory, "numpy")
        return _LOADED[digest]


#: worker-side cache: payload digest -> loaded model
_LOADED: dict[str, Any] = {}

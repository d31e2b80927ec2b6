"""The generated numpy code of a model as bytes: what a worker on any machine needs to evaluate it.

Dask tasks (design sweeps, chunked integrations) carry a :class:`ModelPayload` (the manifest and
the numpy module, a few tens of kB) instead of a path, so the workers of a cluster need symkin
installed but no shared file system.  :meth:`ModelPayload.load` writes it once per machine into
``<symkin cache>/payloads/<digest>`` (the directory of the compiled C libraries,
:func:`symkin.backends.c.build.cache_directory`; the first complete copy renamed into place
wins, so concurrent workers never see half of one) and loads it once per process.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from symkin.manifest import MANIFEST_NAME, read_manifest
from symkin.runtime.info import ModelInfo


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
        info = ModelInfo.from_manifest(read_manifest(directory))
        if "numpy" not in info.backend_files:
            raise ValueError(f"{directory}: no numpy code generated (derive with --backend numpy)")
        names = [MANIFEST_NAME, *info.backend_files["numpy"]]
        return cls(info.name, info.model_hash, tuple((n, (directory / n).read_bytes()) for n in names))

    @functools.cached_property
    def digest(self) -> str:
        """sha256 of the files: the key of the worker-side cache."""
        h = hashlib.sha256()
        for name, content in self.files:
            h.update(name.encode() + b"\0" + content)
        return h.hexdigest()

    def load(self) -> Any:
        """The loaded numpy model (see the module docstring)."""
        digest = self.digest
        if digest not in _LOADED:
            from symkin.runtime.loader import load  # the plain model: workers show no viewer
            from symkin.backends.c.build import cache_directory

            target = cache_directory() / "payloads" / digest[:24]
            if not (target / MANIFEST_NAME).exists():
                target.parent.mkdir(parents=True, exist_ok=True)
                staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
                for name, content in self.files:
                    (staging / name).write_bytes(content)
                try:
                    os.rename(staging, target)
                except OSError:  # another process put its complete copy there first
                    shutil.rmtree(staging, ignore_errors=True)
            _LOADED[digest] = load(target, "numpy")
        return _LOADED[digest]


#: worker-side cache: payload digest -> loaded model
_LOADED: dict[str, Any] = {}

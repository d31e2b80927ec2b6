"""The generated numpy (or JAX) code of a model as bytes: what a worker on any machine needs to evaluate it.

Dask tasks (design sweeps, chunked integrations) carry a :class:`ModelPayload` (the manifest and
the numpy module, a few tens of kB; or the JAX module, for workers with an accelerator) instead of a path, so the workers of a cluster need symkin
installed but no shared file system.  :meth:`ModelPayload.load` writes it once per machine into
``<symkin cache>/payloads/<digest>`` (the directory of the compiled C libraries,
:func:`symkin.backends.c.build.cache_directory`; the first complete copy renamed into place
wins, so concurrent workers never see half of one) and loads it once per process.  Before a copy is imported its
files are compared with the payload's bytes: a folder planted under the payload's name is replaced.
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


#: The backends a payload carries: modules a worker imports without a compiler.
PAYLOAD_BACKENDS = ("numpy", "jax")


@dataclass(frozen=True)
class ModelPayload:
    """The generated numpy (or JAX) code of a model as bytes: what a worker needs to evaluate designs.

    Attributes:
        name: the model name.
        model_hash: the hash of the model source (manifest ``model.hash``).
        files: (file name, content) of the manifest and the backend's module.
        backend: ``numpy`` or ``jax``: what the workers load.
    """

    name: str
    model_hash: str
    files: tuple[tuple[str, bytes], ...]
    backend: str = "numpy"

    @classmethod
    def from_directory(cls, directory: str | Path, backend: str = "numpy") -> ModelPayload:
        directory = Path(directory)
        if backend not in PAYLOAD_BACKENDS:
            raise ValueError(f"a payload carries the {' or the '.join(PAYLOAD_BACKENDS)} code, not {backend!r}")
        info = ModelInfo.from_manifest(read_manifest(directory))
        if backend not in info.backend_files:
            raise ValueError(f"{directory}: no {backend} code generated (derive with --backend {backend})")
        names = [MANIFEST_NAME, *info.backend_files[backend]]
        return cls(info.name, info.model_hash, tuple((n, (directory / n).read_bytes()) for n in names), backend)

    @functools.cached_property
    def digest(self) -> str:
        """sha256 of the files: the key of the worker-side cache."""
        h = hashlib.sha256()
        for name, content in self.files:
            h.update(name.encode() + b"\0" + content)
        return h.hexdigest()

    def load(self) -> Any:
        """The loaded model, on the payload's backend (see the module docstring)."""
        digest = self.digest
        if digest not in _LOADED:
            from symkin.runtime.loader import load  # the plain model: workers show no viewer
            from symkin.backends.c.build import cache_directory
            from symkin.cache_trust import private_directory

            parent = private_directory(private_directory(cache_directory()) / "payloads")
            target = parent / digest[:24]
            if not self._held_by(target):
                staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=parent))
                for name, content in self.files:
                    (staging / name).write_bytes(content)
                aside = parent / f".{target.name}.removed-{os.getpid()}"
                try:
                    if target.exists() or target.is_symlink():  # not this payload's files: planted or damaged
                        os.rename(target, aside)
                    os.rename(staging, target)
                except OSError:  # another process put its complete copy there first
                    shutil.rmtree(staging, ignore_errors=True)
                shutil.rmtree(aside, ignore_errors=True)
                if not self._held_by(target):
                    raise OSError(f"{target}: the payload's files could not be written to the cache")
            _LOADED[digest] = load(target, self.backend)
        return _LOADED[digest]


    def _held_by(self, folder: Path) -> bool:
        """Whether ``folder`` holds exactly this payload's files, byte for byte: the module imported from there is
        the one the payload carries, whoever wrote the folder (a content check, not a name)."""
        try:
            if folder.is_symlink() or not folder.is_dir() or \
                    sorted(p.name for p in folder.iterdir()) != sorted(name for name, _ in self.files):
                return False
            return all((folder / name).read_bytes() == content for name, content in self.files)
        except OSError:
            return False


#: worker-side cache: payload digest -> loaded model
_LOADED: dict[str, Any] = {}

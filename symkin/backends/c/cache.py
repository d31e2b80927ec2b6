"""The C build cache: what it holds, and its eviction (``symkin cache list|clear``).

:func:`symkin.backends.c.build.shared_library` keeps every library it compiles, named
``lib<model>-<key>.so`` after the hash of its source, header, compiler and flags, beside its seal
``<library>.seal`` and a lock file ``<library>.lock`` and, while a build runs, a scratch directory ``<library>.<pid>-<thread>.build``.
Regenerating a model or changing a flag adds a library; nothing removes the old ones, so the
cache grows until it is cleared.  A load touches its library's modification time, so that
"last used" is the time since a program last loaded it.

Eviction is safe while other processes use the cache: a library is removed under its build
lock, taken without waiting (one being built is left alone and reported busy), and a process
that has the library loaded keeps its mapping (POSIX unlink semantics); the next load rebuilds it.
"""

from __future__ import annotations

import re
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from symkin.backends.c.build import SEAL_SUFFIX, cache_directory, locked

#: ``lib<model>-<key>.so``, or ``lib<model>-py-<key>.so`` for the model's CPython entry points.
_LIBRARY = re.compile(r"^lib(?P<model>.+?)(-py)?-(?P<key>[0-9a-f]{24})\.(so|dylib|dll)$")


@dataclass(frozen=True)
class CachedLibrary:
    """A compiled library in the cache: its path, model name, size in bytes and last use (epoch seconds)."""

    path: Path
    model: str
    size: int
    last_used: float


def cached_libraries(directory: Path | None = None) -> list[CachedLibrary]:
    """The libraries in the cache (default :func:`~symkin.backends.c.build.cache_directory`), oldest use first."""
    directory = cache_directory() if directory is None else Path(directory)
    found = []
    for path in directory.iterdir() if directory.is_dir() else ():
        match = _LIBRARY.match(path.name)
        if match and path.is_file():
            stat = path.stat()
            found.append(CachedLibrary(path, match.group("model"), stat.st_size, stat.st_mtime))
    return sorted(found, key=lambda library: (library.last_used, library.path.name))


@dataclass(frozen=True)
class Eviction:
    """What :func:`clear` did: the libraries removed, the bytes freed, the ones left because a build held them."""

    removed: tuple[CachedLibrary, ...]
    freed: int
    busy: tuple[CachedLibrary, ...]


def clear(directory: Path | None = None, *, model: str | None = None, older_than: float | None = None,
          now: float | None = None) -> Eviction:
    """Remove cached libraries (all, or those of ``model``, or those last used more than ``older_than``
    seconds ago), each with its lock file and any scratch directory a crashed build left."""
    directory = cache_directory() if directory is None else Path(directory)
    now = time.time() if now is None else now
    removed, busy, freed = [], [], 0
    for library in cached_libraries(directory):
        if (model is not None and library.model != model) or \
                (older_than is not None and now - library.last_used <= older_than):
            continue
        lock = library.path.with_name(library.path.name + ".lock")
        with locked(lock, wait=False) as free:
            if not free:
                busy.append(library)
                continue
            library.path.unlink(missing_ok=True)
            library.path.with_name(library.path.name + SEAL_SUFFIX).unlink(missing_ok=True)
            for scratch in directory.glob(library.path.name + ".*"):
                if scratch.is_dir():
                    shutil.rmtree(scratch, ignore_errors=True)
            lock.unlink(missing_ok=True)
        removed.append(library)
        freed += library.size
    return Eviction(tuple(removed), freed, tuple(busy))

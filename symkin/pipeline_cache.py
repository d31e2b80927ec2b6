"""The derivation cache: a repeated derive of an unchanged model copies its files instead of deriving (issue 34).

What :mod:`symkin.pipeline` generates is a function of the model file's bytes and name (the manifest records the
name), of the request (the command's options: outputs, backends, folded parameters, scene, robot-file options)
and of the code that derives it (symkin's modules and templates, the sympy, symengine and jinja2 versions).  The
key is the SHA-256 of all of them (:func:`request_key`), so a changed model, request or version misses.  Looking
up a key reads no model and imports no sympy: a hit costs reading the files.

Each entry is a directory ``<cache>/derivations/<model>-<key>/`` (``<cache>``: the C build cache's root,
``SYMKIN_CACHE_DIR``, else ``$XDG_CACHE_HOME/symkin`` or ``~/.cache/symkin``) holding ``entry.json`` (the model
name, the reader's notes, every file's SHA-256) and the files under ``files/``.  An entry is written under a
temporary name and renamed into place, so a reader never sees half of one and two concurrent derives of a model
both succeed (the later rename finds the entry and drops its copy); it is used only when every file's hash
matches, and a corrupted or partial one is removed and derived again.  An entry is code (its numpy module is
imported by the next analysis), so it is sealed (:mod:`symkin.cache_trust`): ``entry.json`` carries an HMAC
of its key, model name, notes and file hashes under a per-user secret kept outside the cache, the folder must
be this user's and writable by nobody else, and the model name must be a model name (it names the folder an
entry is copied to under ``-o``).  A planted or copied entry fails the seal and is derived again.  A hit touches ``entry.json``, so that
``symkin cache list`` shows when an entry was last used and ``symkin cache clear --older-than`` evicts by it.

Robot files that name other files (xacro includes, MJCF ``<include>``) are not cached: their inputs are not all
in the key.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import shutil
import stat
import sys
import tempfile
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path, PurePosixPath
from typing import Any

from symkin import cache_trust
from symkin._version import __version__

#: Version of the entry format (part of the key).
FORMAT = 1
#: The libraries whose versions change what is derived or how it is printed.
DERIVING_LIBRARIES = ("sympy", "symengine", "jinja2")
#: Markers of robot files that pull in other files (not cached).
INCLUDING_MARKERS = (b"xacro", b"<include", b"<mujoco")
ENTRY_FILE = "entry.json"
#: Bytes of a model file beyond which no key is made (the readers refuse files over 1 MB; not imported from
#: symkin.model, which imports sympy, so that a hit does not).
MAX_CACHED_MODEL = 1 << 24
#: Bytes an entry.json may have (symkin writes a few kB).
MAX_ENTRY_RECORD = 1 << 20
#: A model name as :data:`symkin.model.names.IDENTIFIER` admits it (not imported: the CLI imports this module and
#: starts fast): an entry naming anything else was not written by symkin.
MODEL_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")
FILES = "files"
#: How many :func:`bypassed` blocks are running (``--no-cache``).
_bypassing = 0


def enabled() -> bool:
    """False inside :func:`bypassed` (``--no-cache``)."""
    return _bypassing == 0


@contextlib.contextmanager
def bypassed() -> Iterator[None]:
    """While the block runs, commands derive model files afresh and keep nothing (``--no-cache``)."""
    global _bypassing
    _bypassing += 1
    try:
        yield
    finally:
        _bypassing -= 1


def directory(create: bool = True) -> Path:
    """Where the entries live (checked: this user's, writable by nobody else; created mode 0700 with
    ``create``)."""
    from symkin.backends.c.build import cache_directory

    root = cache_trust.private_directory(cache_directory(), create)
    return cache_trust.private_directory(root / "derivations", create)


@lru_cache(maxsize=1)
def code_digest() -> str:
    """SHA-256 of symkin's modules and templates and of the deriving libraries' versions."""
    from importlib import metadata, resources  # here: the CLI imports this module and starts fast

    digest = hashlib.sha256(f"{__version__}\n{sys.version_info[:2]}\n".encode())
    for library in DERIVING_LIBRARIES:
        try:
            digest.update(f"{library}={metadata.version(library)}\n".encode())
        except metadata.PackageNotFoundError:
            digest.update(f"{library}=none\n".encode())
    package = Path(__file__).resolve().parent
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    _digest_tree(digest, resources.files("symkin.templates"), "templates")
    return digest.hexdigest()


def _digest_tree(digest: Any, node: Any, name: str) -> None:
    for child in sorted(node.iterdir(), key=lambda c: c.name):
        if child.is_dir():
            _digest_tree(digest, child, f"{name}/{child.name}")
        elif not child.name.endswith(".pyc"):
            digest.update(f"{name}/{child.name}".encode() + b"\0" + child.read_bytes() + b"\0")


def request_key(path: str | Path, request: Mapping[str, Any]) -> str | None:
    """The key of deriving the model file ``path`` with ``request`` (JSON-able options), or None when the file
    cannot be cached (unreadable: the reader reports it; a robot file that includes others)."""
    try:  # a FIFO or a 5 GB file is not read here: the reader refuses it, located
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_CACHED_MODEL:
            return None
        content = Path(path).read_bytes()
    except OSError:
        return None
    if _may_include(content):
        return None
    text = json.dumps({"format": FORMAT, "file": Path(path).name, "sha256": hashlib.sha256(content).hexdigest(),
                       "request": request, "code": code_digest()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _may_include(content: bytes) -> bool:
    """Whether a model file may pull in other files: any mention of a marker, wherever it stands (a byte-order
    mark or a comment before the root element must not hide a xacro's includes), or text that is not UTF-8
    (UTF-16 XML hides the markers from a byte search)."""
    if any(marker in content.lower() for marker in INCLUDING_MARKERS):
        return True
    try:
        content.decode("utf-8")
    except UnicodeDecodeError:
        return True
    return False


@dataclass(frozen=True)
class Entry:
    """A cached derivation: the model's name, the reader's notes and the generated files (relative path: bytes)."""

    path: Path
    model: str
    notes: tuple[str, ...]
    files: dict[str, bytes]


def lookup(key: str) -> Entry | None:
    """The entry of ``key`` if it is whole (every file present with its recorded hash); a damaged one is removed."""
    try:
        candidates = list(directory().glob(f"*-{key}"))
    except OSError:  # no cache folder can be made (a read-only home): derive
        return None
    for candidate in candidates:
        entry = _read(candidate, key)
        if entry is None:
            _remove(candidate)
            continue
        os.utime(candidate / ENTRY_FILE)
        return entry
    return None


def _read(place: Path, key: str) -> Entry | None:
    """The entry in ``place`` if symkin sealed it there under ``key`` and every file has its recorded hash."""
    try:
        info = (place / ENTRY_FILE).lstat()
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_ENTRY_RECORD:
            return None  # a FIFO would block, a huge file exhaust memory: symkin writes neither
        record = json.loads((place / ENTRY_FILE).read_text(encoding="utf-8"))
        model, notes, hashes = record["model"], record["notes"], record["files"]
        if not (isinstance(model, str) and MODEL_NAME.match(model) and place.name == f"{model}-{key}"
                and isinstance(record["mac"], str)
                and cache_trust.verified(f"derivation {key}", _content_digest(model, notes, hashes), record["mac"])):
            return None
        files = {}
        for name, sha in hashes.items():
            data = (place / FILES / _relative(name)).read_bytes()
            if hashlib.sha256(data).hexdigest() != sha:
                return None
            files[name] = data
        return Entry(place, model, tuple(map(str, notes)), files)
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def _content_digest(model: str, notes: Any, hashes: Any) -> str:
    """SHA-256 of what an entry records (the sealed content)."""
    text = json.dumps({"model": model, "notes": notes, "files": hashes}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _relative(name: str) -> PurePosixPath:
    relative = PurePosixPath(name)
    if relative.is_absolute() or ".." in relative.parts:
        raise ValueError(f"not a relative path: {name}")
    return relative


def store(key: str, model: str, notes: tuple[str, ...], files: Mapping[str, str | bytes]) -> None:
    """Keep a derivation's files under ``key`` (best effort: a cache that cannot be written is no error)."""
    if not MODEL_NAME.match(model):
        return
    try:
        root = directory()
        target = root / f"{model}-{key}"
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=root))
    except OSError:
        return
    try:
        hashes = {}
        for name, content in sorted(files.items()):
            data = content.encode("utf-8") if isinstance(content, str) else content
            path = staging / FILES / _relative(name)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
            hashes[name] = hashlib.sha256(data).hexdigest()
        mac = cache_trust.seal(f"derivation {key}", _content_digest(model, list(notes), hashes))
        (staging / ENTRY_FILE).write_text(json.dumps({"model": model, "notes": list(notes), "files": hashes,
                                                      "mac": mac}, indent=1), encoding="utf-8")
        os.rename(staging, target)  # atomic; fails if a concurrent derive stored the entry first
    except OSError:
        pass
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _remove(place: Path) -> None:
    """Move ``place`` aside (atomic) and delete it, so no reader sees it half removed."""
    aside = place.with_name(f".{place.name}.removed-{os.getpid()}")
    try:
        os.rename(place, aside)
    except OSError:
        return
    shutil.rmtree(aside, ignore_errors=True)


@dataclass(frozen=True)
class CachedDerivation:
    """An entry as ``symkin cache list`` shows it: path, model, size in bytes, last use (epoch seconds)."""

    path: Path
    model: str
    size: int
    last_used: float


def cached_derivations() -> list[CachedDerivation]:
    """The entries, least recently used first."""
    root = directory(create=False)
    found = []
    for place in root.iterdir() if root.is_dir() else ():
        if place.name.startswith(".") or not (place / ENTRY_FILE).is_file():
            continue
        size = sum(p.stat().st_size for p in place.rglob("*") if p.is_file())
        used = (place / ENTRY_FILE).stat().st_mtime
        found.append(CachedDerivation(place, place.name.rsplit("-", 1)[0], size, used))
    return sorted(found, key=lambda entry: (entry.last_used, entry.path.name))


def clear(*, model: str | None = None, older_than: float | None = None, now: float | None = None
          ) -> list[CachedDerivation]:
    """Remove entries (all, those of ``model``, or those last used more than ``older_than`` s ago) and what
    interrupted stores left; returns the removed entries."""
    now = time.time() if now is None else now
    removed = []
    for entry in cached_derivations():
        if (model is not None and entry.model != model) or \
                (older_than is not None and now - entry.last_used <= older_than):
            continue
        _remove(entry.path)
        removed.append(entry)
    root = directory(create=False)
    for leftover in root.glob(".*") if root.is_dir() and model is None and older_than is None else ():
        shutil.rmtree(leftover, ignore_errors=True)
    return removed

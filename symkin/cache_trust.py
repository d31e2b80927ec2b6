"""Trust in the cache folder: what symkin reads back from it is what symkin wrote there (issue 59).

The cache (``SYMKIN_CACHE_DIR``, else ``$XDG_CACHE_HOME/symkin`` or ``~/.cache/symkin``) holds code that runs:
compiled C libraries that are ``dlopen``-ed, generated numpy modules that are imported.  A folder shared with
other users, or restored by CI from an artefact another job wrote, could hold a planted entry; a hash stored in
the entry itself proves nothing, since whoever plants the entry writes the hash too.  Two guards:

1. **The folder** (:func:`private_directory`): the cache root and every folder symkin uses in it must belong to
   this user and be writable by nobody else (no group or other write bit); folders symkin creates get mode
   0700.  A folder that fails is refused (:class:`~symkin.errors.CacheTrustError`, exit 2) with the fix.
2. **The content** (:func:`seal`, :func:`verified`): every entry symkin reads back carries an HMAC-SHA256
   (RFC 2104) under a per-user secret kept *outside* the cache: ``SYMKIN_CACHE_SECRET`` (a file path), else
   ``$XDG_CONFIG_HOME/symkin/cache-secret`` or ``~/.config/symkin/cache-secret`` - 32 random bytes, mode 0600,
   created on first use.  An entry that someone without the secret wrote (a restored CI cache, a copied
   folder) fails the check and is derived or built again.  Where no secret can be kept (a read-only home),
   the process uses one of its own: the cache then serves only what this process wrote.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
from functools import lru_cache
from pathlib import Path

from symkin.errors import CacheTrustError

#: Bytes of the secret.
SECRET_BYTES = 32
#: Write bits that let someone other than the owner change a folder's entries.
FOREIGN_WRITE = stat.S_IWGRP | stat.S_IWOTH


def secret_path() -> Path:
    """Where the per-user secret is kept (see the module docstring)."""
    explicit = os.environ.get("SYMKIN_CACHE_SECRET")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "symkin" / "cache-secret"


def _owned_by_us(info: os.stat_result) -> bool:
    return not hasattr(os, "getuid") or info.st_uid == os.getuid()


@lru_cache(maxsize=4)
def _secret(path: Path) -> bytes:
    try:
        descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    except FileNotFoundError:
        return _created_secret(path)
    except OSError:
        return secrets.token_bytes(SECRET_BYTES)  # unreadable: a secret of this process only
    with os.fdopen(descriptor, "rb") as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode) or not _owned_by_us(info) or info.st_mode & 0o077:
            raise CacheTrustError(
                f"the cache secret {path} is not a private file of this user (mode {stat.filemode(info.st_mode)}): "
                f"anyone who can read it can forge cache entries that run as code\n"
                f"    fix: remove it (symkin makes a new one, mode 0600) or point SYMKIN_CACHE_SECRET at a private file")
        value = handle.read(SECRET_BYTES + 1)
    if len(value) != SECRET_BYTES:
        raise CacheTrustError(f"the cache secret {path} is not {SECRET_BYTES} bytes long\n"
                              f"    fix: remove it; symkin makes a new one")
    return value


def _created_secret(path: Path) -> bytes:
    value = secrets.token_bytes(SECRET_BYTES)
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o600)
    except FileExistsError:  # a concurrent process made it first: use that one
        _secret.cache_clear()
        return _secret(path)
    except OSError:
        return value  # no place to keep it: a secret of this process only
    with os.fdopen(descriptor, "wb") as handle:
        handle.write(value)
    return value


def secret() -> bytes:
    """The per-user secret (read, or created on first use)."""
    return _secret(secret_path())


def seal(label: str, digest: str) -> str:
    """The HMAC of ``label`` (what the entry is: its name and key) and ``digest`` (SHA-256 of its content)."""
    return hmac.new(secret(), f"{label}\0{digest}".encode(), hashlib.sha256).hexdigest()


def verified(label: str, digest: str, mac: str) -> bool:
    """Whether ``mac`` is :func:`seal` of ``label`` and ``digest`` (compared in constant time)."""
    return hmac.compare_digest(seal(label, digest), mac)


def private_directory(path: Path, create: bool = True) -> Path:
    """``path`` as a cache folder: created (mode 0700) if missing (with ``create``; else a missing folder is
    returned as it is: there is nothing in it to trust), else checked to belong to this user and be writable by
    nobody else, and not to be a symbolic link.

    Raises:
        CacheTrustError: the folder belongs to someone else, is writable by others, or is not a folder.
    """
    path = Path(path)
    try:
        if create:
            path.mkdir(mode=0o700, parents=True)
        info = os.lstat(path)
    except FileExistsError:
        info = os.lstat(path)
    except FileNotFoundError:
        if create:
            raise
        return path
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        raise CacheTrustError(f"the cache folder {path} is not a folder but a "
                              f"{'symbolic link' if stat.S_ISLNK(info.st_mode) else 'file'}\n"
                              f"    fix: remove it, or set SYMKIN_CACHE_DIR to a private folder")
    if not _owned_by_us(info) or info.st_mode & FOREIGN_WRITE:
        whose = "belongs to another user" if not _owned_by_us(info) else \
            f"is writable by others (mode {stat.filemode(info.st_mode)})"
        raise CacheTrustError(f"the cache folder {path} {whose}: a file planted there would run as code\n"
                              f"    fix: chmod go-w {path} if it is yours, or set SYMKIN_CACHE_DIR to a private folder")
    return path


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()

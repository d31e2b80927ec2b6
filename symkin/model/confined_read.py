"""Reading the files a model names: regular files only, bounded in size, and only inside the folders it may read.

A model file comes from a stranger (issue 59).  Reading it, and any file it names (a xacro include, a YAML file
through ``load_yaml``, an MJCF include, mesh or texture), must neither block (a FIFO, a device), nor exhaust memory
(a 5 GB file read whole before its size is checked), nor reach outside the folders the user handed over
(``../../etc/passwd``, an absolute path, a symbolic link out of the folder).

* :func:`read_bounded` opens without blocking, refuses anything but a regular file, and reads at most the limit
  plus one byte, so a larger file is refused before it is read;
* :class:`ReadableFolders` is where a robot file may read: its own folder tree, the folder of the ROS package that
  holds it, the package folders the user names (``--xacro-package``) and the folders the user allows
  (``--allow-read DIR``).  A path is checked after every symbolic link in it is resolved, so a link cannot lead
  out.  docs/model-format.md ("What a robot file may read") states the rule for users.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path


class ReadRefused(Exception):
    """A file cannot or may not be read: ``message`` says why, ``fix`` what to do (the caller locates them)."""

    def __init__(self, message: str, fix: str):
        super().__init__(message)
        self.message, self.fix = message, fix


def read_bounded(path: str | Path, limit: int) -> bytes:
    """The bytes of the regular file ``path``, of at most ``limit`` bytes.

    Raises:
        ReadRefused: unreadable, not a regular file (a FIFO, a device, a folder), or larger than ``limit``.
    """
    try:
        descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise ReadRefused(f"cannot read the file {path}: {exc.strerror}", "check the path and the file permissions") from None
    try:
        info = os.fstat(descriptor)
        if not stat.S_ISREG(info.st_mode):
            raise ReadRefused(f"{path} is not a regular file", "name a file (not a folder, FIFO or device)")
        if info.st_size > limit:
            raise ReadRefused(f"{path} has {info.st_size} bytes, more than the limit of {limit}",
                              "a model describes one mechanism; split the file or remove generated content")
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(descriptor, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit:  # it grew while being read
            raise ReadRefused(f"{path} has more than {limit} bytes", "split the file or remove generated content")
        return b"".join(chunks)
    except OSError as exc:
        raise ReadRefused(f"cannot read the file {path}: {exc.strerror}", "check the path and the file permissions") from None
    finally:
        os.close(descriptor)


#: How many folders up from a robot file the ROS package that holds it is looked for (its package.xml).
PACKAGE_LEVELS = 6


def enclosing_package(file: Path) -> Path | None:
    """The nearest folder at or above ``file``'s folder (at most :data:`PACKAGE_LEVELS` up) holding a package.xml:
    the ROS package the file belongs to, whose other files it may read."""
    start = file.resolve().parent
    for folder in [start, *start.parents][:PACKAGE_LEVELS]:
        if (folder / "package.xml").is_file():
            return folder
    return None


@dataclass(frozen=True)
class ReadableFolders:
    """The folders a robot file may read from (each resolved: no symbolic link in it)."""

    folders: tuple[Path, ...]

    @classmethod
    def of(cls, file: str | Path, more: Iterable[str | Path] = ()) -> ReadableFolders:
        """The folder tree of ``file``, the ROS package holding it, and ``more`` (named packages, --allow-read)."""
        main = Path(file)
        folders = [main.resolve().parent]
        package = enclosing_package(main)
        if package is not None:
            folders.append(package)
        folders.extend(Path(folder).resolve() for folder in more)
        return cls(tuple(dict.fromkeys(folders)))

    def with_folder(self, folder: Path) -> ReadableFolders:
        return ReadableFolders(tuple(dict.fromkeys([*self.folders, folder.resolve()])))

    def allows(self, path: Path) -> bool:
        resolved = path.resolve()
        return any(resolved == folder or folder in resolved.parents for folder in self.folders)

    def check(self, path: Path, what: str) -> Path:
        """``path`` resolved, if it lies inside one of the folders.

        Raises:
            ReadRefused: it lies outside them (an absolute path, ``..``, or a symbolic link leading out).
        """
        if not self.allows(path):
            shown = ", ".join(str(folder) for folder in self.folders)
            raise ReadRefused(f"{what} {path} lies outside the folders this robot file may read ({shown})",
                              "keep the files the robot file names beside it, name a ROS package with --xacro-package "
                              "NAME=DIR, or allow a folder with --allow-read DIR")
        return path.resolve()

    def read(self, path: Path, what: str, limit: int) -> bytes:
        """The bytes of ``path`` (checked by :meth:`check`, read by :func:`read_bounded`)."""
        return read_bounded(self.check(path, what), limit)

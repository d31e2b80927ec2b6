"""Write a directory of generated files all at once, or not at all.

Files are written into a temporary sibling directory, which then replaces the target
with two renames while SIGINT/SIGTERM are held back (as is the removal of the previous
output's retired copy), so an interrupted run leaves either the previous or the complete new
output, and no stray directory.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
import threading
from collections.abc import Iterator, Mapping
from pathlib import Path, PurePosixPath

from symkin.errors import ModelError, Problem

_HELD_SIGNALS = {signal.SIGINT, signal.SIGTERM}


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Defer SIGINT and SIGTERM until the block ends (in the main thread; a no-op elsewhere).

    The Python-level handlers are replaced by one that only records the signal, and the
    first recorded signal is raised again, to the restored handler, when the block ends.
    (Blocking with pthread_sigmask would not do: it holds signals back from the calling
    thread only, and the kernel hands a process-directed signal to any other thread - such
    as the progress display's - whose handler then interrupts the main thread anyway.)
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []
    previous = {sig: signal.signal(sig, lambda signum, _frame: received.append(signum)) for sig in _HELD_SIGNALS}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)
        if received:
            signal.raise_signal(received[0])


def _checked_relative(path: str) -> PurePosixPath:
    rel = PurePosixPath(path)
    if rel.is_absolute() or ".." in rel.parts or not rel.parts:
        raise ValueError(f"refusing to write outside the output directory: {path!r}")
    return rel


def file_mode(directory: bool = False) -> int:
    """The mode ``open()`` or ``mkdir()`` would give a new file (0o666) or directory (0o777) under
    the process's umask: outputs staged in private temporary files get it before they are
    renamed into place, so every file symkin writes has the same permissions as any other."""
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if directory else 0o666) & ~mask


def replace_directory(target: Path, files: Mapping[str, str | bytes]) -> None:
    """Make ``target`` a directory holding exactly ``files`` ({relative path: content}).

    Text is written as UTF-8 with '\\n' line ends.  The previous content of ``target``
    stays untouched until every new file has been written and flushed.

    Raises:
        ModelError: ``target`` is a symbolic link or not a directory (it is not silently replaced: a link may
            lead anywhere, and a file is not an earlier output).
    """
    target = Path(target)
    if target.is_symlink() or (target.exists() and not target.is_dir()):
        kind = "a symbolic link" if target.is_symlink() else "not a directory"
        raise ModelError([Problem(str(target), None, None, "", f"the output {target} is {kind}: symkin replaces only "
                                  "a directory it wrote", "remove it, or write elsewhere with -o")])
    parent = target.parent
    parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.tmp-", dir=parent))
    try:
        for name, content in sorted(files.items()):
            path = staging / _checked_relative(name)
            path.parent.mkdir(parents=True, exist_ok=True)
            data = content.encode("utf-8") if isinstance(content, str) else content
            with open(path, "wb") as handle:
                handle.write(data)
                handle.flush()
                os.fsync(handle.fileno())
            os.chmod(path, file_mode())
        os.chmod(staging, file_mode(directory=True))
        with signals_held():
            # the retired copy is removed while signals are still held: a signal delivered right
            # after the swap must not leave it behind
            retired = None
            if target.exists():
                retired = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=parent))
                os.rmdir(retired)
                os.rename(target, retired)
            os.rename(staging, target)
            if retired is not None:
                shutil.rmtree(retired, ignore_errors=True)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def replace_file(target: Path, content: str | bytes) -> None:
    """Make ``target`` a file holding ``content`` (text as UTF-8): written and flushed under a temporary
    name next to it, then renamed into place, so a reader sees the old file or the new one, never half."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, staging = tempfile.mkstemp(prefix=f".{target.name}.tmp-", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(content.encode("utf-8") if isinstance(content, str) else content)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(staging, file_mode())
        os.replace(staging, target)
    except BaseException:
        if os.path.exists(staging):
            os.unlink(staging)
        raise

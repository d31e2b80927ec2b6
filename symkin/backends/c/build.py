"""Compile generated C into a shared library, once: cached by the hash of what goes in.

A generated source states the translation units it splits into (:func:`parts_line`): with
``-D<MODEL>_PART=k`` it keeps function k and the helpers that function uses.  The build
compiles those parts as separate objects in parallel (one compiler process per core, or
``SYMKIN_BUILD_JOBS``) and links them, so the wall time of a build is that of its largest
function rather than the sum; a source without the line (hand-written, or older) is
compiled whole.  The parts hold disjoint functions and each keeps its own static copy of a
helper, so the library has the same code and returns the same bits as the whole file.

The cache key covers the source and header bytes, the compiler command and flags, and the
compiler's version text, so editing any of them (or regenerating the model) builds anew,
while loading the same model again costs a hash and a ``dlopen``.  Libraries are written
under a temporary name and renamed into place, under a lock file, so concurrent loaders
(pytest-xdist workers, several processes of a control application) compile a library once
and never see a half-written file.  A library is code that runs when loaded, so the cache folder must be this
user's and writable by nobody else, and each library carries a seal ``<library>.seal``, an HMAC of its name and
bytes under the per-user secret (:mod:`symkin.cache_trust`): a library without a valid seal (planted, copied
from another machine's cache, or left by a build that died before sealing it) is built again.  Nothing here removes a library: ``symkin cache list|clear``
(:mod:`symkin.backends.c.cache`) shows and evicts them.

Environment:
    SYMKIN_CACHE_DIR: cache directory (default ``$XDG_CACHE_HOME/symkin`` or ``~/.cache/symkin``).
    CC: the C compiler (default ``cc``).
    SYMKIN_CFLAGS: optimization flags (default ``-O3``; e.g. ``-O3 -march=native``).
    SYMKIN_QUIET: ``1`` silences the progress lines a build prints on stderr.
    SYMKIN_BUILD_JOBS: compiler processes at once (default: the cores this process may use).
"""

from __future__ import annotations

import hashlib
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

from symkin import cache_trust
from symkin.atomic import replace_file
from symkin.errors import GeneratedCodeError

DEFAULT_CFLAGS = "-O3"
#: Flags every compilation uses (the generated code must compile warning-free with them).
BASE_FLAGS = ("-std=c99", "-fPIC", "-Wall", "-Wextra")
#: Flags of the CPython extension module (C11: Python's headers need it; numpy's are not warning-free).
EXTENSION_FLAGS = ("-std=c11", "-fPIC", "-Wall")
#: Infix of an extension module's file name in the cache, ``lib<model>-py-<key>.so``.
EXTENSION_TAG = "-py"
#: Suffix of a library's seal (see the module docstring).
SEAL_SUFFIX = ".seal"
#: The generated source's statement of its translation units (see :func:`parts_line`).
_PARTS_PATTERN = re.compile(r"^/\* symkin: translation units (\w+)=0\.\.(\d+) \*/$", re.MULTILINE)


def part_macro(model_name: str) -> str:
    """The macro that selects one translation unit of ``<model>.c``."""
    return f"{model_name.upper()}_PART"


def parts_line(model_name: str, parts: int) -> str:
    """The source line that tells the build it splits into ``parts`` translation units."""
    return f"/* symkin: translation units {part_macro(model_name)}=0..{parts - 1} */"


def translation_units(source_text: str) -> list[list[str]]:
    """The extra compiler arguments of each translation unit of a source: one unit, the whole
    file, unless the source states its parts."""
    match = _PARTS_PATTERN.search(source_text)
    if match is None:
        return [[]]
    macro, last = match.group(1), int(match.group(2))
    return [[f"-D{macro}={k}"] for k in range(last + 1)]


def build_jobs() -> int:
    """Compiler processes run at once."""
    explicit = os.environ.get("SYMKIN_BUILD_JOBS")
    if explicit:
        return max(1, int(explicit))
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def cache_directory() -> Path:
    """Where compiled libraries are kept (see the module docstring)."""
    explicit = os.environ.get("SYMKIN_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "symkin"


def compiler_command() -> list[str]:
    """The compiler and the user's optimization flags."""
    return shlex.split(os.environ.get("CC", "cc")) + shlex.split(os.environ.get("SYMKIN_CFLAGS", DEFAULT_CFLAGS))


@lru_cache(maxsize=8)
def _compiler_version(compiler: str) -> str:
    try:
        result = subprocess.run([compiler, "--version"], capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError) as exc:
        raise GeneratedCodeError(f"cannot run the C compiler '{compiler}' ({exc}); install one (e.g. gcc) "
                                 "or set CC to a C compiler") from None
    return result.stdout


def _library_suffix() -> str:
    return ".dylib" if sys.platform == "darwin" else ".dll" if sys.platform == "win32" else ".so"


def shared_library(source: Path, header: Path) -> Path:
    """The compiled shared library of ``source`` (building it if the cache has none).

    Raises:
        GeneratedCodeError: the compiler is missing or fails (its messages are included).
    """
    command = compiler_command()
    key = _key(source.read_bytes(), header.read_bytes(), "\0".join(command + list(BASE_FLAGS)).encode(),
               _compiler_version(command[0]).encode())
    directory = cache_trust.private_directory(cache_directory())

    def build(target: Path) -> None:
        units = translation_units(source.read_text())
        jobs = min(build_jobs(), len(units))
        progress(f"symkin: compiling {source.name} ({source.stat().st_size // 1024} kB, "
                 f"{len(units)} translation unit{'s' if len(units) > 1 else ''}, {jobs} at once) with "
                 f"{' '.join(command)}; cached in {directory} afterwards ...")
        _compile(command, [(list(BASE_FLAGS) + ["-I", str(header.parent)] + unit, source) for unit in units],
                 target, jobs, ["-lm"])

    return _cached(directory / f"lib{source.stem}-{key}{_library_suffix()}", build, source.name)


def _key(*parts: bytes) -> str:
    """The cache key of what goes into a build: 24 hex digits of the SHA-256 of the parts' digests."""
    key = hashlib.sha256()
    for part in parts:
        key.update(hashlib.sha256(part).digest())
    return key.hexdigest()[:24]


def _cached(target: Path, build: Callable[[Path], None], what: str) -> Path:
    """``target`` from the cache (its use recorded) if its seal holds, or made by ``build(target)`` and sealed under
    its build lock, once however many processes ask at the same time; the time it took goes to stderr."""
    if _sealed(target):
        _touch(target)
        return target
    with locked(target.parent / f"{target.name}.lock"):
        if not _sealed(target):  # another process may have built it while we waited
            start = time.perf_counter()
            build(target)
            replace_file(_seal_path(target), cache_trust.seal(f"library {target.name}", cache_trust.file_digest(target)))
            progress(f"symkin: compiled {what} in {time.perf_counter() - start:.1f} s")
    return target


def _seal_path(library: Path) -> Path:
    return library.with_name(library.name + SEAL_SUFFIX)


def _sealed(library: Path) -> bool:
    """Whether ``library`` is a regular file that symkin built and sealed (see the module docstring)."""
    try:
        if not library.is_file() or library.is_symlink():
            return False
        mac = _seal_path(library).read_text(encoding="ascii")[:128]
        return cache_trust.verified(f"library {library.name}", cache_trust.file_digest(library), mac)
    except (OSError, UnicodeDecodeError):
        return False


def python_include_directories() -> tuple[str, str] | None:
    """The C header directories of this Python (with Python.h) and of numpy, or None without Python.h."""
    import sysconfig

    import numpy

    python = sysconfig.get_paths().get("include")
    if not python or not (Path(python) / "Python.h").is_file():
        return None
    return python, numpy.get_include()


def extension_module(source: Callable[[], str], what: bytes, model: str, header: Path,
                     library: Path) -> tuple[Path, str]:
    """The compiled CPython extension module of the C source ``source()`` (which includes ``header``), linked to
    the model's ``library``, and its module name: from the cache, or built there.  The key: ``what`` (all that
    decides the source, so that a cached module is found without rendering it), the header, the library's path
    (itself named by its key), the compiler, its flags and version, the header directories.

    Raises:
        GeneratedCodeError: no Python headers, or the compiler is missing or fails.
    """
    includes = python_include_directories()
    if includes is None:
        raise GeneratedCodeError("this Python has no C headers (Python.h)")
    command = compiler_command()
    digest = _key(what, header.read_bytes(), str(library).encode(),
                  "\0".join(command + list(EXTENSION_FLAGS) + list(includes)).encode(),
                  _compiler_version(command[0]).encode())
    name = f"_symkin_{model}_{digest}"

    def build(target: Path) -> None:
        progress(f"symkin: compiling the CPython entry points of {model} with {' '.join(command)} ...")
        flags = [*EXTENSION_FLAGS, "-I", str(header.parent), "-I", includes[0], "-I", includes[1],
                 f'-DSYMKIN_MODULE_NAME="{name}"', f"-DSYMKIN_MODULE_INIT=PyInit_{name}"]
        _compile(command, [(flags, source())], target, 1, [str(library), "-lm"])

    target = cache_trust.private_directory(cache_directory()) / f"lib{model}{EXTENSION_TAG}-{digest}{_library_suffix()}"
    return _cached(target, build, f"the entry points of {model}"), name


def progress(line: str) -> None:
    """A progress line on stderr: a build takes seconds, loading from the cache is silent
    (``SYMKIN_QUIET=1`` silences builds too)."""
    if os.environ.get("SYMKIN_QUIET", "") not in ("", "0"):
        return
    print(line, file=sys.stderr, flush=True)


def _touch(library: Path) -> None:
    """Record a use of ``library`` (its modification time, the "last used" of ``symkin cache``); a
    read-only cache keeps the old time."""
    try:
        os.utime(library)
    except OSError:
        pass


@contextmanager
def locked(path: Path, wait: bool = True) -> Iterator[bool]:
    """An exclusive lock on ``path`` (so concurrent loaders compile a library once), held for the
    block; yields True.  With ``wait=False`` it yields False at once, holding nothing, if another
    process has the lock (``symkin cache clear`` leaves a library being built alone)."""
    try:
        import fcntl
    except ImportError:  # no advisory locks (Windows): concurrent builds stay safe, just redundant
        yield True
        return
    with open(path, "a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        try:
            yield True
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


class _Compilers:
    """The compiler processes of one build, each in a process group of its own.

    An interrupted build (Ctrl-C) kills every running compiler with its children (the assembler,
    the linker: killing the driver alone let a linker write into the scratch directory after it was
    removed) and waits for them, so nothing writes into the cache once the build has stopped.
    """

    def __init__(self) -> None:
        self.running: set[subprocess.Popen[str]] = set()
        self.lock = threading.Lock()

    def run(self, arguments: list[str], source: Path) -> None:
        process = subprocess.Popen(arguments, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                   start_new_session=True)
        with self.lock:
            self.running.add(process)
        try:
            _, err = process.communicate()
        finally:
            with self.lock:
                self.running.discard(process)
        if process.returncode != 0:
            raise GeneratedCodeError(f"compiling {source} failed:\n{err.strip()}")

    def kill(self) -> None:
        with self.lock:
            running = list(self.running)
        for process in running:
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        for process in running:
            process.wait()


def _compile(command: list[str], units: list[tuple[list[str], Path | str]], target: Path, jobs: int,
             link: list[str]) -> None:
    """Compile each unit (its flags and its source: a file, or C text) into an object, link them with ``link``
    into a temporary file next to ``target``, then rename it into place (so no reader ever sees a half-written
    library)."""
    # named before it exists, so that an interrupt at any point (the progress line has just been printed,
    # Ctrl-C often lands here) leaves nothing: the finally block knows the name even if mkdir was the last step
    # (the build lock makes this process and thread the only builder of ``target``)
    scratch = target.parent / f"{target.name}.{os.getpid()}-{threading.get_ident()}.build"
    compilers = _Compilers()
    try:
        shutil.rmtree(scratch, ignore_errors=True)  # left by a killed process that had this pid
        scratch.mkdir()
        objects = [str(scratch / f"part{k}.o") for k in range(len(units))]
        sources = []
        for k, (_flags, source) in enumerate(units):
            if isinstance(source, str):
                text, source = source, scratch / f"unit{k}.c"
                source.write_text(text, encoding="utf-8")
            sources.append(source)
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            try:
                # list() re-raises the first failure once every started compilation has finished
                list(pool.map(lambda unit, source, obj: compilers.run(
                    command + unit[0] + ["-c", "-o", obj, str(source)], source), units, sources, objects))
            except BaseException:
                compilers.kill()  # before the pool waits for its threads, which wait for their compilers
                raise
        partial = scratch / target.name
        try:
            compilers.run(command + ["-shared", "-o", str(partial)] + objects + link, target)
        except BaseException:
            compilers.kill()
            raise
        os.replace(partial, target)
    finally:
        # The compilers are dead (killed on an interruption) but the file system may lag behind: never let
        # that leave the scratch directory in the cache (or hide the KeyboardInterrupt behind an OSError).
        for _ in range(20):
            shutil.rmtree(scratch, ignore_errors=True)
            if not scratch.exists():
                break
            time.sleep(0.05)

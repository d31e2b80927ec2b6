"""Compile an MJCF file with MuJoCo, confined: its files checked first, the compiler run in a bounded subprocess.

MuJoCo's compiler follows ``<include file>``, meshes, textures, height fields, skins and attached models
wherever their paths lead, and it runs in-process: a file that makes it crash (a model asset that attaches
itself) ends the interpreter, and size bombs (``replicate``, ``size nkey``, ``flexcomp``, ``hfield``) hang it or
exhaust memory.  So (issue 59):

1. :func:`prescan` reads the file and every file it includes (expat, DTDs refused, each a bounded regular file,
   at most :data:`MAX_FILES`) and checks every path an element names (an attribute ``file``, ``file...``, or
   ``...dir`` of ``<compiler>``): resolved against each folder MuJoCo may resolve it from (the main file's,
   the including file's, with the compiler's ``meshdir``/``texturedir``/``assetdir``), every reading must lie
   inside the folders the robot file may read (:class:`~symkin.model.confined_read.ReadableFolders`), and
   count attributes whose product sizes the model (``replicate count``, ``flexcomp count``, ``hfield nrow ncol``,
   ``size`` entries) are bounded;
2. :func:`compile_confined` runs MuJoCo's compiler in a child process (``python -m symkin.model.mjcf_compile``)
   with an address-space limit of :data:`MEMORY_BYTES` and a time limit of :data:`SECONDS`, which writes the
   compiled model as MJB; a crash, a hang or the memory limit becomes a located refusal, and the parent loads
   the MJB, which MuJoCo itself wrote.  MuJoCo's warnings (which it would append to a ``MUJOCO_LOG.TXT`` in the
   working directory) come back with it, for the model's notes.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat

from symkin.errors import ModelError, Problem
from symkin.model.confined_read import ReadableFolders, ReadRefused

#: Files an MJCF file may pull in through ``<include>`` (itself included).
MAX_FILES = 100
#: Elements of all files together.
MAX_ELEMENTS = 200_000
#: Bound on a count attribute's product (replicated bodies, flex vertices, height-field samples, size entries).
MAX_COUNT = 1_000_000
#: The compiler's address space and wall time.
MEMORY_BYTES = 4 << 30
SECONDS = 60
#: Attributes that name a folder (``<compiler>``) prefixed to asset paths.
_FOLDER_ATTRIBUTES = ("meshdir", "texturedir", "assetdir")
#: Attributes whose values multiply into a size, by element.
_COUNTS = {"replicate": ("count",), "flexcomp": ("count",), "composite": ("count",), "hfield": ("nrow", "ncol"),
           "size": ("nkey", "nuserdata", "nuser_body", "nuser_jnt", "nuser_geom", "nuser_site", "nuser_cam",
                    "nuser_tendon", "nuser_actuator", "nuser_sensor", "nconmax", "njmax", "nstack")}
_INTEGER = re.compile(r"^\s*\d{1,18}\s*$")


@dataclass
class _Scan:
    main: Path
    readable: ReadableFolders
    files: list[Path] = field(default_factory=list)
    elements: int = 0
    folders: dict[str, str] = field(default_factory=dict)  # compiler meshdir/texturedir/assetdir
    references: list[tuple[str, str, str, int, int]] = field(default_factory=list)  # (attr, value, file, line, col)


def _refuse(file: str, line: int | None, column: int | None, message: str, fix: str) -> ModelError:
    return ModelError([Problem(file, line, column, "", message, fix)])


def prescan(path: Path, readable: ReadableFolders) -> list[Path]:
    """Check ``path`` and what it includes and names (see the module docstring); returns the files read.

    Raises:
        ModelError: a file outside the readable folders, not a regular file, too large or malformed, too many
            files or elements, a count beyond :data:`MAX_COUNT` - located.
    """
    from symkin.model.yaml_source import MAX_FILE_BYTES

    scan = _Scan(path, readable)
    pending: list[tuple[Path, str, int | None, int | None]] = [(path, str(path), None, None)]
    while pending:
        file, where, line, column = pending.pop()
        if file.resolve() in scan.files:
            continue  # included twice (or in a cycle, which MuJoCo refuses): scanned once
        if len(scan.files) >= MAX_FILES:
            raise _refuse(where, line, column, f"the file includes more than {MAX_FILES} files",
                          "include fewer files (or check for an include cycle)")
        try:
            raw = readable.read(file, "the included file", MAX_FILE_BYTES) if scan.files else \
                readable.read(file, "the file", MAX_FILE_BYTES)
        except ReadRefused as exc:
            raise _refuse(where, line, column, exc.message, exc.fix) from None
        scan.files.append(file.resolve())
        pending.extend(_scan_file(raw, file, scan))
    for attribute, value, file_name, line_number, column_number in scan.references:
        _check_reference(scan, attribute, value, Path(file_name), line_number, column_number)
    return scan.files


def _scan_file(raw: bytes, file: Path, scan: _Scan) -> list[tuple[Path, str, int | None, int | None]]:
    """Scan one file's elements; returns its includes (path, file, line, column)."""
    parser = expat.ParserCreate()
    includes: list[tuple[Path, str, int | None, int | None]] = []
    stack: list[int] = [1]  # product of the enclosing replicate counts

    def refuse(*_args: Any) -> None:
        raise _refuse(str(file), parser.CurrentLineNumber, parser.CurrentColumnNumber + 1,
                      "document type declarations are not allowed", "remove the DOCTYPE")

    def start(tag: str, attrib: dict[str, str]) -> None:
        line, column = parser.CurrentLineNumber, parser.CurrentColumnNumber + 1
        scan.elements += 1
        if scan.elements > MAX_ELEMENTS:
            raise _refuse(str(file), line, column, f"the model has more than {MAX_ELEMENTS} elements",
                          "remove generated content")
        product = stack[-1]
        for name in _COUNTS.get(tag, ()):
            if name in attrib:
                product *= _count(attrib[name], str(file), line, column, f"{tag} {name}")
        if product > MAX_COUNT:
            raise _refuse(str(file), line, column, f"<{tag}> sizes the model to more than {MAX_COUNT} entries "
                          f"({product})", "use smaller counts")
        stack.append(product if tag == "replicate" else stack[-1])
        if tag == "compiler":
            for name in _FOLDER_ATTRIBUTES:
                if name in attrib:
                    scan.folders[name] = attrib[name]
                    scan.references.append((name, attrib[name], str(file), line, column))
        for name, value in attrib.items():
            if name.startswith("file"):
                scan.references.append((f"{tag} {name}", value, str(file), line, column))
                if tag == "include":
                    candidates = _candidates(scan, value, file, "")
                    found = [c for c in candidates if c.is_file()] or candidates[:1]
                    includes.extend((c, str(file), line, column) for c in found)
            elif name.endswith("dir") and tag != "compiler":
                scan.references.append((f"{tag} {name}", value, str(file), line, column))

    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    parser.StartElementHandler = start
    parser.EndElementHandler = lambda _tag: stack.pop()
    try:
        parser.Parse(raw, True)
    except expat.ExpatError as exc:
        raise _refuse(str(file), exc.lineno, exc.offset + 1, f"malformed XML: {expat.ErrorString(exc.code)}",
                      "fix the XML syntax") from None
    return includes


def _count(text: str, file: str, line: int, column: int, what: str) -> int:
    values = text.split()
    if not values or not all(_INTEGER.match(v) for v in values):
        raise _refuse(file, line, column, f"{what}='{text[:40]}' is not a list of non-negative integers",
                      "write whole numbers")
    product = 1
    for value in values:
        product *= max(int(value), 1)
        if product > MAX_COUNT:
            raise _refuse(file, line, column, f"{what}='{text[:40]}' sizes the model to more than {MAX_COUNT} "
                          "entries", "use smaller counts")
    return product


def _candidates(scan: _Scan, value: str, file: Path, prefix_attribute: str) -> list[Path]:
    """Every path MuJoCo may read for ``value`` named in ``file``: from the main file's folder or the naming
    file's, under the compiler's folder for its kind (``meshdir`` ...) and ``assetdir`` or none."""
    prefixes = {""} | {scan.folders[name] for name in (prefix_attribute, "assetdir") if name in scan.folders}
    bases = dict.fromkeys([scan.main.parent, file.parent])  # the main file's folder first
    return [base / prefix / value for base in bases for prefix in sorted(prefixes)]


def _check_reference(scan: _Scan, attribute: str, value: str, file: Path, line: int, column: int) -> None:
    kind = "texturedir" if attribute.startswith(("texture", "skin")) else \
        "meshdir" if attribute.startswith(("mesh", "hfield")) else ""
    for candidate in _candidates(scan, value, file, kind):
        if not scan.readable.allows(candidate):
            raise _refuse(str(file), line, column,
                          f"{attribute}='{value[:200]}' names {candidate}, outside the folders this robot file may "
                          f"read ({', '.join(str(f) for f in scan.readable.folders)})",
                          "keep the files the MJCF file names beside it, or allow a folder with --allow-read DIR")


def compile_confined(path: Path, readable: ReadableFolders) -> tuple[Any, list[str]]:
    """The compiled ``mujoco.MjModel`` of ``path`` and MuJoCo's warnings (see the module docstring).

    Raises:
        ModelError: a refused file (:func:`prescan`), MuJoCo's compiler refusing the file (its message), or the
            compiler crashing, running out of memory or time - located in the file.
    """
    import mujoco

    prescan(path, readable)
    with tempfile.TemporaryDirectory(prefix="symkin-mjcf-") as scratch:
        binary = Path(scratch) / "model.mjb"
        command = [sys.executable, "-m", "symkin.model.mjcf_compile", str(path.resolve()), str(binary)]
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=SECONDS, cwd=scratch,
                                    env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
        except subprocess.TimeoutExpired:
            raise _refuse(str(path), None, None, f"MuJoCo's compiler ran longer than {SECONDS} s on the file",
                          "check the file's sizes (replicate, flexcomp, hfield, size) and its meshes") from None
        if result.returncode == 0:
            try:
                warnings = [str(w) for w in json.loads(result.stdout.strip().splitlines()[-1])["warnings"]]
            except (IndexError, ValueError, KeyError, TypeError):
                warnings = []
            return mujoco.MjModel.from_binary_path(str(binary)), warnings
        try:
            refusal = json.loads(result.stdout.strip().splitlines()[-1])["refused"]
        except (IndexError, ValueError, KeyError, TypeError):
            signal = -result.returncode if result.returncode < 0 else None
            how = f"crashed (signal {signal})" if signal else f"failed (exit {result.returncode})"
            raise _refuse(str(path), None, None, f"MuJoCo's compiler {how} on the file, or exceeded its "
                          f"{MEMORY_BYTES >> 30} GiB of memory", "fix the MJCF file (it must load in MuJoCo: "
                          "check self-referencing assets and sizes)") from None
        raise _refuse(str(path), None, None, f"MuJoCo's compiler refuses the file: {refusal}",
                      "fix the MJCF file (it must load in MuJoCo)")


def _limits() -> None:
    """The child's own bounds, set before MuJoCo is imported (not by preexec_fn, unsafe beside threads)."""
    try:
        import resource
    except ImportError:  # not POSIX: the wall-time limit remains
        return
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_BYTES, MEMORY_BYTES))
    resource.setrlimit(resource.RLIMIT_CPU, (SECONDS, SECONDS))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def _main(argv: list[str]) -> int:
    """The child: compile argv[0], save the MJB to argv[1]; a refusal is printed as JSON on stdout."""
    _limits()
    import mujoco

    warnings: list[str] = []
    mujoco.set_mju_user_warning(lambda text: warnings.append(" ".join(str(text).split())[:500]))
    try:
        model = mujoco.MjModel.from_xml_path(argv[0])
    except ValueError as exc:  # MuJoCo's compiler errors name the element and its line
        print(json.dumps({"refused": " ".join(str(exc).split())[:2000]}))
        return 3
    mujoco.mj_saveModel(model, argv[1], None)
    print(json.dumps({"warnings": list(dict.fromkeys(warnings))[:20]}))
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))

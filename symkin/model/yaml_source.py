"""Read a YAML model file into plain data that remembers where every value came from.

A model file is data, never code: the file is *composed* (parsed into a node graph) with
PyYAML's safe loader, and the node graph is converted by hand, so no constructor of any
tag ever runs.  On the way the reader

* rejects explicit tags (``!!python/object``...), merge keys and non-string keys,
* rejects duplicate keys (PyYAML would silently keep the last one),
* bounds the file size, the nesting depth and the number of nodes after alias expansion
  (so a "billion laughs" document fails fast instead of eating memory),
* records for every key path its line/column and, for scalars, the raw text, so that
  numbers such as ``0.1807`` reach the expression parser as written (exact decimals).

Key paths are tuples of str (mapping keys) and int (sequence indices).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from symkin.errors import ModelError, Problem

MAX_FILE_BYTES = 1_000_000
MAX_NODES = 100_000
MAX_DEPTH = 64
#: Bracket depth at which a file is refused before YAML parsing (a generous multiple of
#: MAX_DEPTH, so that brackets inside quoted text never trip it in a sensible file).
PRESCAN_DEPTH = 4 * MAX_DEPTH

KeyPath = tuple[str | int, ...]

_CORE = "tag:yaml.org,2002:"
_SCALAR_TAGS = {_CORE + t for t in ("str", "int", "float", "bool", "null")}


#: Longest echo of a user's value in a message (a 5000-digit number or a 100 kB key is cut).
MAX_ECHO = 60


def shorten(text: object, limit: int = MAX_ECHO) -> str:
    """``text`` as a string of at most ``limit`` characters (the middle elided)."""
    text = str(text)
    if len(text) <= limit:
        return text
    half = (limit - 5) // 2
    return f"{text[:half]} ... {text[-half:]} ({len(text)} characters)"


def format_path(path: KeyPath) -> str:
    """Render a key path as ``serial.dh.rows[2].alpha``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + shorten(part)
    return out


def located_problem(file: str, mark: tuple[Any, ...] | None, key: str, message: str, fix: str) -> Problem:
    """A :class:`Problem` at ``mark``: (line, column) in ``file``, (line, column, other file), or None."""
    if mark is None:
        return Problem(file, None, None, key, message, fix)
    return Problem(mark[2] if len(mark) > 2 else file, mark[0], mark[1], key, message, fix)


@dataclass
class Document:
    """Plain data of a YAML file plus the location and raw text of every value.

    Attributes:
        file: the path as given by the user (used in messages).
        data: the document as dict/list/str/int/float/bool/None.
        marks: key path -> (line, column), 1-based, or (line, column, file) where the value was written in
            another file than ``file`` (an element of an included xacro file).
        raw: key path -> raw scalar text, for scalars.
        reduction: for a URDF source, how its tree became the chain
            (:class:`symkin.model.urdf_source.UrdfReduction`); None for a YAML file.
    """

    file: str
    data: Any
    marks: dict[KeyPath, tuple[Any, ...]] = field(default_factory=dict)
    raw: dict[KeyPath, str] = field(default_factory=dict)
    reduction: Any = None

    def problem(self, path: KeyPath, message: str, fix: str) -> Problem:
        """A :class:`Problem` located at ``path`` (or at its closest located ancestor)."""
        probe = tuple(path)
        while probe and probe not in self.marks:
            probe = probe[:-1]
        return located_problem(self.file, self.marks.get(probe), format_path(path), message, fix)

    def canonical_json(self, omit: tuple[str, ...] = ()) -> str:
        """The data as canonical JSON (sorted keys) without the top-level keys ``omit``: the input of the model hash."""
        data = {key: value for key, value in self.data.items() if key not in omit} if isinstance(self.data, dict) \
            else self.data
        return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def read_document(path: str | Path) -> Document:
    """Read and compose a YAML model file.

    Raises:
        ModelError: unreadable file, YAML syntax error, or forbidden YAML construct.
    """
    name = str(path)
    raw_bytes = model_file_bytes(path)
    try:
        text = raw_bytes.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ModelError([Problem(name, None, None, "", f"the file is not UTF-8 text ({exc.reason} at byte {exc.start})",
                                  "save the model as UTF-8 text")]) from None
    return parse_document(text, name)


def model_file_bytes(path: str | Path) -> bytes:
    """The bytes of the model file ``path``: a regular file of at most :data:`MAX_FILE_BYTES` bytes, refused before
    it is read if larger (a 5 GB file must not exhaust memory, a FIFO must not block).

    Raises:
        ModelError: unreadable, not a regular file, or too large.
    """
    from symkin.model.confined_read import ReadRefused, read_bounded

    try:
        return read_bounded(path, MAX_FILE_BYTES)
    except ReadRefused as exc:
        raise ModelError([Problem(str(path), None, None, "", exc.message, exc.fix)]) from None


def parse_document(text: str, file: str = "<string>") -> Document:
    """Compose YAML ``text`` into a :class:`Document` (see module docstring for the rules)."""
    line, column = _deepest_point(text, PRESCAN_DEPTH)
    if line is not None:  # refuse before PyYAML, whose time grows with the square of the flow depth
        raise ModelError([Problem(file, line, column, "", f"the document is nested deeper than {MAX_DEPTH} levels",
                                  "flatten the structure; no model key nests this deep")])
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow, e.g. a NUL byte
        line, column = _line_column(text, exc.position)
        code = ord(exc.character) if isinstance(exc.character, str) else int(exc.character)
        raise ModelError([Problem(file, line, column, "", f"the character U+{code:04X} is not allowed in a YAML file",
                                  "remove it: a model file is plain text (no NUL or other control characters)")]) from None
    except RecursionError:
        line, column = _deepest_point(text)
        if line is None:  # nested by indentation: the first line indented more than MAX_DEPTH
            deep = [i for i, row in enumerate(text.splitlines(), 1) if len(row) - len(row.lstrip(" ")) > MAX_DEPTH]
            line, column = (deep[0], MAX_DEPTH + 1) if deep else (None, None)
        raise ModelError([Problem(file, line, column, "", f"the document is nested deeper than {MAX_DEPTH} levels",
                                  "flatten the structure; no model key nests this deep")]) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (None, None)
        context = exc.context or ""
        if exc.context and exc.context_mark and exc.problem_mark and exc.context_mark.line != exc.problem_mark.line:
            context += f" (opened at line {exc.context_mark.line + 1})"
        detail = ": ".join(s for s in (context, exc.problem) if s)
        raise ModelError([Problem(file, line, col, "", f"YAML syntax error: {detail}",
                                  "fix the YAML syntax at this line (indentation, quotes, colons)")]) from None
    except yaml.YAMLError as exc:  # e.g. several documents in one stream
        raise ModelError([Problem(file, None, None, "", f"YAML error: {exc}",
                                  "a model file must hold exactly one YAML document")]) from None
    if root is None:
        raise ModelError([Problem(file, None, None, "", "the file is empty",
                                  "write a model: see docs/model-format.md")])
    doc = Document(file, None)
    converter = _Converter(doc)
    doc.data = converter.convert(root, (), 0)
    if converter.problems:
        raise ModelError(converter.problems)
    return doc


def _line_column(text: str, position: int) -> tuple[int, int]:
    """1-based line and column of the character at ``position``."""
    before = text[:position]
    line = before.count("\n") + 1
    return line, position - (before.rfind("\n") + 1) + 1


def _deepest_point(text: str, limit: int = MAX_DEPTH) -> tuple[int | None, int | None]:
    """Where flow brackets ([ and {, quotes not considered) first nest deeper than ``limit``, or (None, None)."""
    depth = 0
    for position, char in enumerate(text):
        if char in "[{":
            depth += 1
            if depth > limit:
                return _line_column(text, position)
        elif char in "]}":
            depth -= 1
    return None, None


class _Converter:
    """Walks a composed node graph into plain data, enforcing the safety rules."""

    def __init__(self, doc: Document):
        self.doc = doc
        self.nodes = 0
        self.open: set[int] = set()  # ids of the collection nodes being converted (alias cycles)
        self.problems: list[Problem] = []
        self.scalar_constructor = yaml.constructor.SafeConstructor()

    def _fail(self, node: yaml.Node, path: KeyPath, message: str, fix: str) -> None:
        mark = node.start_mark
        self.problems.append(Problem(self.doc.file, mark.line + 1, mark.column + 1,
                                     format_path(path), message, fix))

    def convert(self, node: yaml.Node, path: KeyPath, depth: int) -> Any:
        self.nodes += 1
        if self.nodes > MAX_NODES:
            self._fail(node, path, f"the document expands to more than {MAX_NODES} values "
                                   "(aliases expanding exponentially?)",
                       "remove the anchors/aliases that multiply the document")
            raise ModelError(self.problems)
        if depth > MAX_DEPTH:
            self._fail(node, path, f"the document is nested deeper than {MAX_DEPTH} levels",
                       "flatten the structure; no model key nests this deep")
            raise ModelError(self.problems)
        self.doc.marks.setdefault(path, (node.start_mark.line + 1, node.start_mark.column + 1))
        if isinstance(node, yaml.ScalarNode):
            return self._scalar(node, path)
        if id(node) in self.open:
            self._fail(node, path, "an alias refers to a node that contains it (a recursive structure)",
                       "remove the alias ('*name') inside the anchored ('&name') value")
            raise ModelError(self.problems)
        self.open.add(id(node))
        try:
            if isinstance(node, yaml.SequenceNode):
                if node.tag != _CORE + "seq":
                    return self._bad_tag(node, path)
                return [self.convert(item, path + (i,), depth + 1) for i, item in enumerate(node.value)]
            if isinstance(node, yaml.MappingNode):
                if node.tag != _CORE + "map":
                    return self._bad_tag(node, path)
                return self._mapping(node, path, depth)
        finally:
            self.open.discard(id(node))
        self._fail(node, path, "unsupported YAML node", "use plain mappings, lists and scalars")
        return None

    def _bad_tag(self, node: yaml.Node, path: KeyPath) -> None:
        self._fail(node, path, f"YAML tag '{node.tag}' is not allowed (a model file is data, never code)",
                   "remove the tag; write plain values")
        return None

    def _scalar(self, node: yaml.ScalarNode, path: KeyPath) -> Any:
        if node.tag not in _SCALAR_TAGS:
            return self._bad_tag(node, path)
        self.doc.raw[path] = node.value
        kind = node.tag[len(_CORE):]
        if kind == "str":
            return node.value
        if kind == "null":
            return None
        constructor = yaml.constructor.SafeConstructor.yaml_constructors[node.tag]
        try:
            return constructor(self.scalar_constructor, node)
        except (ValueError, OverflowError, yaml.YAMLError):
            self._fail(node, path, f"cannot read the {kind} value '{shorten(node.value)}'", f"write a plain {kind}")
            return None

    def _mapping(self, node: yaml.MappingNode, path: KeyPath, depth: int) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for key_node, value_node in node.value:
            if key_node.tag == _CORE + "merge":
                self._fail(key_node, path, "YAML merge keys ('<<') are not supported",
                           "write the keys out explicitly")
                continue
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag != _CORE + "str":
                self._fail(key_node, path, f"mapping keys must be plain strings, got '{shorten(getattr(key_node, 'value', '?'))}'",
                           "quote the key or rename it to a plain word")
                continue
            key = key_node.value
            if key in out:
                first = self.doc.marks.get(path + (key,), (0, 0))[0]
                self._fail(key_node, path + (key,), f"duplicate key '{shorten(key)}' (first defined on line {first})",
                           "remove one of the two definitions")
                continue
            self.doc.marks[path + (key,)] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
            out[key] = self.convert(value_node, path + (key,), depth + 1)
        return out

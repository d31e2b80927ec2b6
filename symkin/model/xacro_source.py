"""Expand a xacro robot description into URDF text without running anything it contains.

Most ROS robot descriptions ship as xacro: XML with macros (``<xacro:macro>``), properties
(``<xacro:property>``), arguments (``<xacro:arg>``, ``$(arg NAME)``), conditionals
(``<xacro:if>``, ``<xacro:unless>``), includes (``$(find PACKAGE)``) and ``${...}`` expressions.
The reference implementation (the ``xacro`` package) evaluates ``${...}`` with Python's ``eval``;
a robot file comes from strangers, so symkin expands xacro itself (issue 29), with the expression
language of :mod:`symkin.model.xacro_expressions`, which runs nothing a file says.

Semantics follow xacro 2 (in-order processing, the ROS wiki's "xacro" page):

* properties are lazy: ``value`` is stored as text and evaluated (in the scope that defines
  it) where it is first used; a text that is a single ``${...}`` keeps its type, numbers and
  ``true``/``false`` texts become numbers and booleans, ``'quoted'`` texts lose their quotes;
  ``default=`` defines a property only if it is undefined; ``scope="parent"|"global"``;
  a property without a value holds its child elements (a block);
* macros bind ``params`` (``p``, ``p:=default``, ``p:=^`` and ``p:=^|default`` from the caller's
  property, ``*block`` one child element of the call, ``**block`` the children of one child
  element); the body is expanded in a scope under the caller's (xacro's dynamic scoping);
  ``<xacro:call macro="...">`` calls a macro by computed name;
* ``$(find PACKAGE)`` is the directory given by ``packages`` (``--xacro-package NAME=DIR``), or
  else the nearest ROS package PACKAGE (a directory holding a ``package.xml`` whose ``<name>`` is
  PACKAGE) among the file's ancestor directories and their children - never a directory merely so
  named (``$(find etc)`` is not ``/etc``); ``$(arg NAME)`` the value
  given by ``args`` (``--xacro-arg NAME:=VALUE``) or the ``<xacro:arg default>``; ``$(dirname)``
  the directory of the file; ``$(eval EXPR)`` an expression; ``$(env ...)``/``$(optenv ...)``
  are refused (a model must not depend on the environment: pass the value as an argument);
* includes (``<xacro:include filename ns>``) read ``.xacro``, ``.urdf`` and ``.xml`` files only,
  each bounded in size like a model file; ``xacro.load_yaml``/``load_yaml`` reads ``.yaml``
  files with the safe loader, aliases refused (a few lines of aliases expand to billions of nodes);
* every file read lies inside the folders the robot file may read
  (:class:`~symkin.model.confined_read.ReadableFolders`: its own folder tree, the ROS package
  holding it, the packages ``$(find)`` resolves to, and ``--allow-read`` folders), is a regular
  file, and is bounded in size before it is read.

The output is URDF text with one element per line, and its line map
(:class:`~symkin.model.generated_urdf.GeneratedUrdf`) leads each output line back to the element
of the xacro file it came from, so that the URDF reader's messages point into the xacro source.

Length: one expander of one format (scopes, properties, macros, includes, substitutions and the
line map), whose parts only make sense together; the expression language is its own module.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat
from xml.sax.saxutils import escape, quoteattr

import yaml

from symkin.errors import ModelError, Problem, name_list
from symkin.model.confined_read import ReadableFolders, ReadRefused, read_bounded
from symkin.model.generated_urdf import GeneratedUrdf, read_generated_urdf
from symkin.model.xacro_expressions import (MAX_TEXT, Evaluator, XacroFail, as_text, boolean, literal, namespaced,
                                           pieces)
from symkin.model.yaml_source import MAX_FILE_BYTES, Document

#: Elements and characters the expansion may produce (as the URDF reader's bounds: a file of at most ten
#: model files' size), macro and property depth, includes.
MAX_ELEMENTS = 100_000
MAX_OUTPUT = 10 * MAX_FILE_BYTES
MAX_DEPTH = 100
MAX_INCLUDES = 500
#: Macro calls of one expansion (a macro that calls itself twice, 60 deep, is 2^60 calls), nesting of XML elements.
MAX_CALLS = 100_000
MAX_XML_DEPTH = 200
#: An XML name (element or attribute): what a computed name must be, so that it cannot write markup.
_XML_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.:-]{0,127}$")
#: Characters of an element's text kept (URDF holds numbers in attributes; a transmission's reduction is text).
MAX_TEXT_KEPT = 256
#: Directories above the file, and children of each, searched for a package (``$(find NAME)``).
PACKAGE_SEARCH_LEVELS = 6
PACKAGE_SEARCH_CHILDREN = 1000
#: Bytes of a package.xml read for its <name>.
MAX_PACKAGE_XML = 65536
INCLUDE_SUFFIXES = (".xacro", ".urdf", ".xml")
YAML_SUFFIXES = (".yaml", ".yml")

_XACRO = "xacro:"
_DIRECTIVES = frozenset({"property", "arg", "macro", "include", "if", "unless", "insert_block", "element",
                         "attribute", "call"})


@dataclass
class _Node:
    """An XML element of a xacro file, with where it was written."""

    tag: str
    attrib: dict[str, str]
    file: str
    line: int
    column: int
    children: list[_Node] = field(default_factory=list)
    #: True once expanded (blocks are expanded in the caller's scope before a macro inserts them).
    expanded: bool = False
    #: its character data, stripped (a transmission's ``<mechanicalReduction>${ratio}</...>``), bounded.
    text: str = ""
    #: elements in its subtree once expanded (itself included).
    size: int = 1


@dataclass
class _Property:
    raw: Any
    evaluated: bool
    node: _Node | None
    busy: bool = False


@dataclass
class _Macro:
    name: str
    params: list[tuple[str, str | None]]  # (name with its * or ** prefix, default text or None)
    body: list[_Node]


class _Scope:
    """Properties and macros of one scope; lookups walk up to the global scope."""

    def __init__(self, parent: _Scope | None = None):
        self.parent = parent
        self.properties: dict[str, _Property] = {}
        self.macros: dict[str, _Macro] = {}

    @property
    def root(self) -> _Scope:
        scope = self
        while scope.parent is not None:
            scope = scope.parent
        return scope

    def find(self, name: str) -> tuple[_Scope, _Property] | None:
        scope: _Scope | None = self
        while scope is not None:
            if name in scope.properties:
                return scope, scope.properties[name]
            scope = scope.parent
        return None

    def macro(self, name: str) -> _Macro | None:
        scope: _Scope | None = self
        while scope is not None:
            if name in scope.macros:
                return scope.macros[name]
            scope = scope.parent
        return None


def expand_xacro(path: str | Path, args: Mapping[str, str] | None = None,
                 packages: Mapping[str, str | Path] | None = None,
                 allow_read: Sequence[str | Path] = ()) -> GeneratedUrdf:
    """Expand the xacro file ``path`` (see the module docstring).

    Args:
        args: values of ``<xacro:arg>`` (``--xacro-arg NAME:=VALUE``).
        packages: {package: directory} for ``$(find package)`` (``--xacro-package NAME=DIR``).
        allow_read: more folders the file may read from (``--allow-read DIR``).

    Raises:
        ModelError: unreadable, malformed or unsupported xacro, or a file named outside the folders it may read,
            located in the file that has it.
    """
    named = {k: Path(v).resolve() for k, v in (packages or {}).items()}
    expander = _Expander(Path(path), dict(args or {}), named,
                         ReadableFolders.of(path, [*named.values(), *allow_read]))
    try:
        root = expander.parse(Path(path), str(path))
        scope = _Scope()
        children = expander.expand_children(root, scope, Path(path))
        unused = sorted(set(expander.args) - expander.declared_args)
        if unused:
            raise XacroFail(f"--xacro-arg {unused[0]} names no <xacro:arg> of the file",
                        f"declared arguments: {name_list(sorted(expander.declared_args)) or 'none'}", root)
        out_root = _Node(root.tag, {k: v for k, v in root.attrib.items() if not k.startswith("xmlns:xacro")},
                         root.file, root.line, root.column, children)
        lines: list[str] = ['<?xml version="1.0"?>']
        where: list[tuple[str, int, int]] = [(root.file, root.line, root.column)]
        _write(out_root, 0, lines, where)
    except RecursionError:  # elements nested by macros beyond Python's stack
        raise ModelError([Problem(str(path), None, None, "", "the expansion nests elements too deeply",
                                  "flatten the macros that wrap elements in elements")]) from None
    except XacroFail as exc:
        node = exc.node
        raise ModelError([Problem(node.file if node else str(path), node.line if node else None,
                                  node.column if node else None, "", exc.message, exc.fix)]) from None
    return GeneratedUrdf("\n".join(lines) + "\n", tuple(where))


def _write(node: _Node, depth: int, lines: list[str], where: list[tuple[str, int, int]]) -> None:
    attributes = "".join(f" {name}={quoteattr(value)}" for name, value in node.attrib.items())
    indent = "  " * depth
    where.append((node.file, node.line, node.column))
    if node.text and not node.children:
        lines.append(f"{indent}<{node.tag}{attributes}>{escape(node.text)}</{node.tag}>")
        return
    if not node.children:
        lines.append(f"{indent}<{node.tag}{attributes}/>")
        return
    lines.append(f"{indent}<{node.tag}{attributes}>")
    for child in node.children:
        _write(child, depth + 1, lines, where)
    lines.append(f"{indent}</{node.tag}>")
    where.append((node.file, node.line, node.column))


class _Expander:
    """One expansion: the files read, the arguments, the element count."""

    def __init__(self, main: Path, args: dict[str, str], packages: dict[str, Path], readable: ReadableFolders):
        self.main, self.args, self.packages, self.readable = main, args, packages, readable
        self.declared_args: set[str] = set()
        self.arg_values: dict[str, str] = {}
        self.elements = 0
        self.characters = 0
        self.includes = 0
        self.calls = 0
        self.depth = 0

    # ------------------------------------------------------------------ reading

    def parse(self, path: Path, name: str, at: _Node | None = None) -> _Node:
        """The element tree of the XML file ``path`` (inside the readable folders, DTDs refused, size bounded)."""
        try:
            raw = self.readable.read(path, "the included file", MAX_FILE_BYTES) if at is not None else \
                read_bounded(path, MAX_FILE_BYTES)
        except ReadRefused as exc:
            raise XacroFail(exc.message, exc.fix, at) from None
        parser = expat.ParserCreate()
        stack: list[_Node] = []
        roots: list[_Node] = []

        def refuse(*_args: Any) -> None:
            raise XacroFail("document type declarations are not allowed", "remove the DOCTYPE",
                        _Node("", {}, name, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1))

        def start(tag: str, attrib: dict[str, str]) -> None:
            node = _Node(tag, dict(attrib), name, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
            if len(stack) >= MAX_XML_DEPTH:
                raise XacroFail(f"the XML nests deeper than {MAX_XML_DEPTH} elements", "flatten the file", node)
            (stack[-1].children if stack else roots).append(node)
            stack.append(node)

        def characters(data: str) -> None:
            if stack and len(stack[-1].text) < MAX_TEXT_KEPT:
                stack[-1].text = (stack[-1].text + data)[:MAX_TEXT_KEPT]

        parser.StartDoctypeDeclHandler = refuse
        parser.EntityDeclHandler = refuse
        parser.StartElementHandler = start
        parser.CharacterDataHandler = characters
        parser.EndElementHandler = lambda _tag: stack.pop()
        try:
            parser.Parse(raw, True)
        except RecursionError:
            raise XacroFail("the XML nests too deeply", "flatten the file", _Node("", {}, name, 1, 1)) from None
        except expat.ExpatError as exc:
            raise XacroFail(f"malformed XML: {expat.ErrorString(exc.code)}", "fix the XML syntax",
                        _Node("", {}, name, exc.lineno, exc.offset + 1)) from None
        return roots[0]

    # ------------------------------------------------------------------ expansion

    def expand_children(self, node: _Node, scope: _Scope, file: Path) -> list[_Node]:
        out: list[_Node] = []
        for child in node.children:
            out.extend(self.expand(child, scope, file, node))
        return out

    def expand(self, node: _Node, scope: _Scope, file: Path, parent: _Node) -> list[_Node]:
        """The elements ``node`` becomes in ``scope`` (``parent`` takes xacro:attribute)."""
        if node.expanded:  # a block inserted again: its elements are written again
            self.count(node, node.size)
            return [node]
        if not node.tag.startswith(_XACRO):
            self.count(node, 1)
            attrib = {k: self.text(v, scope, file, node) for k, v in node.attrib.items()
                      if not k.startswith("xmlns:xacro")}
            self.characters += sum(len(v) for v in attrib.values())
            if self.characters > MAX_OUTPUT:
                raise XacroFail(f"the expansion grows beyond {MAX_OUTPUT} characters", "check for runaway macros",
                                node)
            result = _Node(node.tag, attrib, node.file, node.line, node.column, expanded=True,
                           text=self.text(node.text.strip(), scope, file, node) if node.text.strip() else "")
            result.children = self.expand_children(node, scope, file)
            for child in node.children:  # <xacro:attribute> of this element
                if child.tag == _XACRO + "attribute":
                    name = self.text(self.need(child, "name"), scope, file, child)
                    if not _XML_NAME.match(name):
                        raise XacroFail(f"'{name[:60]}' is not an XML attribute name", "name attributes with letters, "
                                        "digits, _ . - and :", child)
                    result.attrib[name] = self.text(self.need(child, "value"), scope, file, child)
            result.size = 1 + sum(child.size for child in result.children)
            return [result]
        kind = node.tag[len(_XACRO):]
        if kind == "property":
            self.define_property(node, scope, file)
        elif kind == "arg":
            name = self.need(node, "name")
            self.declared_args.add(name)
            if name not in self.arg_values:
                if name in self.args:
                    self.arg_values[name] = self.args[name]
                elif "default" in node.attrib:
                    self.arg_values[name] = as_text(self.text(node.attrib["default"], scope, file, node))
        elif kind == "macro":
            scope.macros[self.need(node, "name")] = _Macro(self.need(node, "name"),
                                                            _params(node.attrib.get("params", ""), node),
                                                            node.children)
        elif kind == "include":
            return self.include(node, scope, file)
        elif kind in ("if", "unless"):
            value = boolean(self.value(self.need(node, "value"), scope, file, node), node)
            if value == (kind == "if"):
                return self.expand_children(node, scope, file)
        elif kind == "insert_block":
            found = scope.find(self.text(self.need(node, "name"), scope, file, node))
            if found is None or not isinstance(found[1].raw, list):
                raise XacroFail(f"<xacro:insert_block name=\"{node.attrib['name']}\"> names no block", "pass the block "
                            "as a *param of the macro, or define it with <xacro:property name=...> and content", node)
            return [n for block in found[1].raw for n in self.expand(block, scope, file, parent)]
        elif kind == "element":
            name = self.text(self.need(node, "xacro:name"), scope, file, node)
            if not _XML_NAME.match(name):  # a computed name: it must not write markup (a parsed tag is a name)
                raise XacroFail(f"'{name[:60]}' is not an XML element name", "name elements with letters, digits, "
                                "_ . - and :", node)
            renamed = _Node(name, {k: v for k, v in node.attrib.items() if k != "xacro:name"}, node.file, node.line,
                            node.column, node.children)
            return self.expand(renamed, scope, file, parent)
        elif kind == "attribute":
            pass  # applied by the parent element
        elif kind == "call":
            return self.call(self.text(self.need(node, "macro"), scope, file, node), node, scope, file, parent,
                             skip={"macro"})
        else:
            return self.call(kind, node, scope, file, parent, skip=set())
        return []

    def count(self, node: _Node, elements: int) -> None:
        """Count ``elements`` more elements written (bounded by :data:`MAX_ELEMENTS`)."""
        self.elements += elements
        if self.elements > MAX_ELEMENTS:
            raise XacroFail(f"the expansion has more than {MAX_ELEMENTS} elements", "check for runaway macros", node)

    def need(self, node: _Node, attribute: str) -> str:
        if attribute not in node.attrib:
            raise XacroFail(f"<{node.tag}> has no '{attribute}' attribute", f"add {attribute}=\"...\"", node)
        return node.attrib[attribute]

    def define_property(self, node: _Node, scope: _Scope, file: Path) -> None:
        name = self.need(node, "name")
        if not name.isidentifier():
            raise XacroFail(f"property name '{name}' is not an identifier", "name it with letters, digits and _", node)
        target = {"parent": scope.parent or scope, "global": scope.root}.get(node.attrib.get("scope", ""), scope)
        if "value" in node.attrib:
            raw: Any = node.attrib["value"]
        elif "default" in node.attrib:
            if scope.find(name) is not None:
                return
            raw = node.attrib["default"]
        else:
            raw = node.children
            target.properties[name] = _Property(raw, True, node)
            return
        prop = _Property(raw, False, node)
        target.properties[name] = prop
        if node.attrib.get("lazy_eval", "true").lower() in ("false", "0"):
            self.resolve(prop, scope, file)

    def resolve(self, prop: _Property, scope: _Scope, file: Path) -> Any:
        """The value of a property, evaluated once, in the scope that defines it."""
        if prop.evaluated:
            return prop.raw
        if prop.busy:
            raise XacroFail("circular property definition", "define the property without referring to itself", prop.node)
        prop.busy = True
        self.enter(prop.node)
        try:
            prop.raw = literal(self.value(prop.raw, scope, file, prop.node))
        finally:
            self.depth -= 1
            prop.busy = False
        prop.evaluated = True
        return prop.raw

    def enter(self, node: _Node | None) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise XacroFail(f"macros or properties nest deeper than {MAX_DEPTH}", "remove the recursion", node)

    def include(self, node: _Node, scope: _Scope, file: Path) -> list[_Node]:
        self.includes += 1
        if self.includes > MAX_INCLUDES:
            raise XacroFail(f"more than {MAX_INCLUDES} includes", "check for an include cycle", node)
        target = self.path(self.text(self.need(node, "filename"), scope, file, node), file, node, INCLUDE_SUFFIXES)
        included = self.parse(target, str(target), node)
        inner = scope
        if "ns" in node.attrib:
            inner = _Scope(scope)
            namespace = self.text(node.attrib["ns"], scope, file, node)
            scope.properties[namespace] = _Property(_ScopeView(inner, self, target), True, node)
        self.enter(node)
        try:
            return self.expand_children(included, inner, target)
        finally:
            self.depth -= 1

    def path(self, text: str, file: Path, node: _Node, suffixes: tuple[str, ...]) -> Path:
        target = Path(text)
        if not target.is_absolute():
            target = file.parent / target
        if target.suffix.lower() not in suffixes:
            raise XacroFail(f"'{text}' is not a {'/'.join(suffixes)} file", "include robot description files only", node)
        return target

    def call(self, name: str, node: _Node, scope: _Scope, file: Path, parent: _Node, skip: set[str]) -> list[_Node]:
        if name in _DIRECTIVES - {"call"}:
            raise XacroFail(f"<xacro:{name}> is misplaced", "see the xacro documentation", node)
        macro = scope.macro(name)
        if macro is None:
            raise XacroFail(f"no macro named '{name}' is defined here", "define it with <xacro:macro name=\"" + name +
                        "\"> before this call, or include the file that does", node)
        self.calls += 1
        if self.calls > MAX_CALLS:
            raise XacroFail(f"more than {MAX_CALLS} macro calls", "check for macros that call themselves", node)
        inner = _Scope(scope)
        given = {k: v for k, v in node.attrib.items() if k not in skip}
        blocks = [child for child in node.children]
        names = {param.lstrip("*") for param, _ in macro.params}
        unknown = sorted(set(given) - names)
        if unknown:
            raise XacroFail(f"macro '{name}' has no parameter '{unknown[0]}'",
                        f"its parameters: {name_list(sorted(names)) or 'none'}", node)
        for param, default in macro.params:
            if param.startswith("*"):
                if not blocks:
                    raise XacroFail(f"macro '{name}' needs the block {param}", "give it as a child element of the call",
                                node)
                block = blocks.pop(0)
                content = [block] if not param.startswith("**") else block.children
                expanded = [n for child in content for n in self.expand(child, scope, file, parent)]
                inner.properties[param.lstrip("*")] = _Property(expanded, True, node)
            elif param in given:
                inner.properties[param] = _Property(literal(self.value(given[param], scope, file, node)), True, node)
            elif default is not None and default.startswith("^"):
                found = scope.find(param)
                if found is not None:
                    inner.properties[param] = _Property(self.resolve(found[1], found[0], file), True, node)
                elif "|" in default:
                    inner.properties[param] = _Property(default.split("|", 1)[1], False, node)
                else:
                    raise XacroFail(f"macro '{name}' takes '{param}' from the caller, which has no such property",
                                f"pass {param}=\"...\"", node)
            elif default is not None:
                inner.properties[param] = _Property(default, False, node)
            else:
                raise XacroFail(f"macro '{name}' needs the parameter '{param}'", f"add {param}=\"...\" to the call", node)
        self.enter(node)
        try:
            return [n for child in macro.body for n in self.expand(child, inner, file, parent)]
        finally:
            self.depth -= 1

    # ------------------------------------------------------------------ text and expressions

    def text(self, text: str, scope: _Scope, file: Path, node: _Node) -> str:
        """``text`` with every ``${...}`` and ``$(...)`` replaced by its value's text."""
        return as_text(self.value(text, scope, file, node))

    def value(self, text: Any, scope: _Scope, file: Path, node: _Node | None) -> Any:
        """The value of ``text``: typed if it is one ``${...}``, else the substituted text."""
        if not isinstance(text, str):
            return text
        parts = list(pieces(text, node))
        values = [self.piece(kind, body, scope, file, node) for kind, body in parts]
        if len(values) == 1 and parts[0][0] == "${":
            return values[0]
        joined = "".join(v if isinstance(v, str) else as_text(v) for v in values)
        if len(joined) > MAX_TEXT:
            raise XacroFail(f"a text grows beyond {MAX_TEXT} characters", "shorten it", node)
        return joined

    def piece(self, kind: str, body: str, scope: _Scope, file: Path, node: _Node | None) -> Any:
        if kind == "text":
            return body
        if kind == "$(":
            return self.substitution(body, scope, file, node)
        try:
            tree = ast.parse(body.strip(), mode="eval")
        except (RecursionError, MemoryError):
            raise XacroFail("the expression nests too deeply", "split it into properties", node) from None
        except SyntaxError:
            raise XacroFail(f"'${{{body}}}' is not an expression", "write a Python-style arithmetic expression",
                        node) from None
        return Evaluator(lambda name: self.lookup(name, scope, file, node),
                         lambda name: self.load_yaml(name, file, node), node).eval(tree.body)

    def lookup(self, name: str, scope: _Scope, file: Path, node: _Node | None) -> Any:
        """The value of the property ``name`` seen from ``scope``, or None if there is none."""
        found = scope.find(name)
        if found is None:
            return None
        value = self.resolve(found[1], found[0], file)
        if isinstance(value, list) and value and all(isinstance(v, _Node) for v in value):
            raise XacroFail(f"'{name}' is a block, not a value", f"insert it with <xacro:insert_block name=\"{name}\"/>",
                            node)
        return value

    def substitution(self, body: str, scope: _Scope, file: Path, node: _Node | None) -> str:
        """``$(find P)``, ``$(arg A)``, ``$(dirname)``, ``$(eval E)``."""
        command, _, rest = body.strip().partition(" ")
        rest = rest.strip()
        if command == "arg":
            if rest in self.arg_values:
                return self.arg_values[rest]
            if rest in self.args:
                return self.args[rest]
            raise XacroFail(f"$(arg {rest}) has no value", f"pass --xacro-arg {rest}:=VALUE, or declare "
                                                       f"<xacro:arg name=\"{rest}\" default=\"...\"/> before it", node)
        if command == "find":
            return str(self.find(rest, file, node))
        if command == "dirname":
            return str(file.parent.resolve())
        if command == "eval":
            return as_text(self.value("${" + rest + "}", scope, file, node))
        if command in ("env", "optenv"):
            raise XacroFail(f"$({command} ...) reads the environment, which a model file must not depend on",
                        "replace it by an <xacro:arg> and pass --xacro-arg NAME:=VALUE", node)
        raise XacroFail(f"unknown substitution $({command} ...)", "use $(arg NAME), $(find PACKAGE), $(dirname) or "
                                                              "$(eval EXPR)", node)

    def find(self, package: str, file: Path, node: _Node | None) -> Path:
        """The folder of the ROS package ``package``: named by the user, or a folder with a package.xml naming it
        around the file (then readable too)."""
        if package in self.packages:
            return self.packages[package]
        for start in (file.parent.resolve(), self.main.parent.resolve()):
            for ancestor in [start, *start.parents][:PACKAGE_SEARCH_LEVELS]:
                for candidate in _package_candidates(ancestor):
                    if candidate.parent != candidate and _package_name(candidate) == package:
                        self.packages[package] = candidate
                        self.readable = self.readable.with_folder(candidate)
                        return candidate
        raise XacroFail(f"cannot find the ROS package '{package}' near the file (a folder with a package.xml naming "
                        "it)", f"pass --xacro-package {package}=DIRECTORY", node)

    def load_yaml(self, name: Any, file: Path, node: _Node | None) -> Any:
        target = self.path(str(name), file, node or _Node("", {}, str(file), 0, 0), YAML_SUFFIXES)
        try:
            raw = self.readable.read(target, "the YAML file", MAX_FILE_BYTES)
        except ReadRefused as exc:
            raise XacroFail(exc.message, exc.fix, node) from None
        try:
            return namespaced(yaml.load(raw, Loader=_AliasFreeLoader))
        except RecursionError:
            raise XacroFail(f"{target} nests too deeply", "flatten the YAML file", node) from None
        except yaml.YAMLError as exc:
            raise XacroFail(f"{target} is not valid YAML: {exc}", "fix the YAML file", node) from None


class _ScopeView:
    """A ``ns`` of ``<xacro:include ns=...>``: its properties as attributes of the name."""

    def __init__(self, scope: _Scope, expander: _Expander, file: Path):
        self.scope, self.expander, self.file = scope, expander, file

    def attribute(self, name: str, node: Any) -> Any:
        if name in self.scope.properties:
            return self.expander.resolve(self.scope.properties[name], self.scope, self.file)
        raise XacroFail(f"the namespace has no property '{name}'", "check the included file", node)


def _params(text: str, node: _Node) -> list[tuple[str, str | None]]:
    params: list[tuple[str, str | None]] = []
    if text.count("'") % 2 or text.count('"') % 2:
        raise XacroFail(f"the macro parameters '{text}' have an unclosed quote", "close the quote", node)
    for item in _PARAM.findall(text):  # a quoted default stays whole: xyz:='0 0 0'
        name, sep, default = item.partition(":=")
        if not name.lstrip("*").isidentifier():
            raise XacroFail(f"macro parameter '{item}' is not a name", "write params=\"a b:=1 *block\"", node)
        params.append((name, default if sep else None))
    return params


_PARAM = re.compile(r"(?:[^\s'\"]|'[^']*'|\"[^\"]*\")+")


def _package_candidates(directory: Path) -> Iterator[Path]:
    yield directory
    try:
        children = sorted(p for p in directory.iterdir() if p.is_dir())[:PACKAGE_SEARCH_CHILDREN]
    except OSError:
        return
    yield from children


_PACKAGE_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


def _package_name(directory: Path) -> str | None:
    """The <name> in the directory's package.xml (None without one, or if it is no small regular file)."""
    if not (directory / "package.xml").is_file():
        return None
    try:
        text = read_bounded(directory / "package.xml", MAX_PACKAGE_XML).decode("utf-8", errors="replace")
    except ReadRefused:
        return None
    found = _PACKAGE_NAME.search(text)
    return found.group(1) if found else None


class _AliasFreeLoader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses aliases (``*name``): a few lines of them expand to billions of nodes."""

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            raise yaml.composer.ComposerError(None, None, "aliases (*name) are not allowed here",
                                              self.peek_event().start_mark)
        return super().compose_node(parent, index)


def read_xacro_document(path: str | Path, args: Mapping[str, str] | None = None,
                        packages: Mapping[str, str | Path] | None = None, allow_read: Sequence[str | Path] = (),
                        **urdf: Any) -> tuple[Document, str]:
    """(model document, expanded URDF text) of the xacro file ``path``: :func:`expand_xacro`, then the URDF
    reader (``urdf``: its tip, base, locks and snap_angles), whose messages point into the xacro files."""
    expansion = expand_xacro(path, args, packages, allow_read)
    return read_generated_urdf(expansion, str(path), **urdf), expansion.text

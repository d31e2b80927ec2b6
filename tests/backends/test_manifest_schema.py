"""One manifest schema (issue 35): the manifest is the types of symkin/manifest_schema.py (:class:`Manifest` and
its records), which symkin/manifest.py builds and serializes and symkin/runtime/info.py
(:class:`~symkin.runtime.info.ModelInfo`, the typed view every consumer reads) parses; the manifest's keys are
read in the schema and in manifest.py's version check, nowhere else.

A reader elsewhere that indexes the manifest by key strings (``manifest["functions"]``,
``manifest.get("backends")``) breaks silently when the writer changes: there is none, and the backends' loaders
bind each generated function from its typed record (``ModelInfo.functions``), not from the manifest's dicts.  An
old manifest is refused with a message that says to derive again, wherever it is read.
"""

from __future__ import annotations

import ast
import json
import shutil

import pytest

from conftest import GENERATED_DIR, ROOT
from symkin.errors import GeneratedCodeError

#: Where the manifest's key strings belong: the writer and the typed reader.
SCHEMA = {"symkin/manifest.py", "symkin/manifest_schema.py"}
#: The keys of a generated function's record (:func:`symkin.manifest.build_manifest`): outside :data:`SCHEMA` the
#: runtime reads them as the fields of ``runtime.info.Function``, ``Input`` and ``Output``.
RECORD_KEYS = {"inputs", "outputs", "summary", "kind", "shape", "elements", "units", "unit", "default", "doc"}


def _is_manifest(node: ast.AST) -> bool:
    """Whether an expression is a manifest or a part of one reached by keys (``manifest``, ``x.manifest``,
    ``manifest["model"]``)."""
    if isinstance(node, ast.Subscript):
        return _is_manifest(node.value)
    if isinstance(node, ast.Name):
        return "manifest" in node.id
    return isinstance(node, ast.Attribute) and node.attr == "manifest"


def _key_reads(tree: ast.AST) -> int:
    """Reads of a manifest by a key string: ``m["key"]`` and ``m.get("key", ...)``."""
    count = 0
    for node in ast.walk(tree):
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) \
                and isinstance(node.slice.value, str) and _is_manifest(node.value):
            count += 1
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
                and _is_manifest(node.func.value) and node.args and isinstance(node.args[0], ast.Constant):
            count += 1
    return count


def key_readers() -> dict[str, int]:
    """{module path: reads of the manifest by key strings} outside :data:`SCHEMA`."""
    found = {}
    for path in sorted((ROOT / "symkin").rglob("*.py")):
        name = path.relative_to(ROOT).as_posix()
        if name in SCHEMA:
            continue
        count = _key_reads(ast.parse(path.read_text()))
        if count:
            found[name] = count
    return found


def test_only_the_schema_reads_the_manifest_by_its_keys():
    found = key_readers()
    assert not found, f"read the manifest through runtime.info.ModelInfo (add what is missing there): {found}"


def record_key_reads(tree: ast.AST) -> int:
    """Subscripts by a key of a function record (``record["inputs"]``, ``i["kind"]``)."""
    return sum(1 for node in ast.walk(tree)
               if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant)
               and node.slice.value in RECORD_KEYS)


def test_the_loaders_read_typed_function_records():
    """The backends' loaders and wrappers bind each function from ``ModelInfo.functions`` (typed), not from dicts."""
    found = {path.name: count for path in sorted((ROOT / "symkin" / "runtime").glob("*.py"))
             if path.name != "info.py" and (count := record_key_reads(ast.parse(path.read_text())))}
    assert not found, f"read the function's fields of runtime.info.Function instead: {found}"
    assert record_key_reads(ast.parse('n = record["inputs"][0]["shape"]\nk = i.kind')) == 2


def test_the_finder_sees_each_form_of_a_key_read():
    source = 'a = manifest["model"]["name"]\nb = self.manifest.get("backends", {})\nc = info.backend_files["c"]'
    assert _key_reads(ast.parse(source)) == 3  # the nested read counts twice; info.backend_files is typed


def test_an_old_manifest_is_refused_by_every_reader_with_a_rederive_message(tmp_path):
    from symkin import load
    from symkin.runtime.payload import ModelPayload

    directory = tmp_path / "planar_2r"
    shutil.copytree(GENERATED_DIR / "planar_2r", directory)
    manifest = json.loads((directory / "manifest.json").read_text())
    manifest["manifest_version"] = 0
    (directory / "manifest.json").write_text(json.dumps(manifest))
    for read in (load, ModelPayload.from_directory):
        with pytest.raises(GeneratedCodeError, match="derive the model again with this symkin"):
            read(directory)


@pytest.mark.parametrize("directory", sorted(p.parent.name for p in GENERATED_DIR.glob("*/manifest.json")))
def test_a_written_manifest_is_its_type_serialized(directory):
    """The writer serializes the schema's types and the reader parses them: every manifest of the example models
    is ``Manifest.from_record(manifest).to_record()``, key order included (the bytes of generated/ are checked by
    tests/backends/test_golden.py), and so is each record alone."""
    from symkin.manifest import dumps
    from symkin.manifest_schema import Coordinate, Function, Manifest

    text = (GENERATED_DIR / directory / "manifest.json").read_text()
    manifest = json.loads(text)
    assert dumps(Manifest.from_record(manifest).to_record()) == text
    for kind, record in [(Function, r) for r in manifest["functions"]] + \
            [(Coordinate, r) for r in manifest["model"]["coordinates"]]:
        assert json.dumps(kind.from_record(record).to_record()) == json.dumps(record), (kind.__name__, record)

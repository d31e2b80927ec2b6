"""A test module imports no other test module (issue 35): sample models shared by several modules live in
tests/sample_models.py, shared checks in tests/checks.py, the identification runs in tests/identification_runs.py,
fixtures for all in conftest.py.  A model defined in one test module and imported by another hides where it is
used and runs that module's imports (and its module-level work) in the other.
"""

from __future__ import annotations

import ast

from conftest import ROOT


def imported_test_modules(source: str) -> set[str]:
    """The test modules (``test_*``) a module's source imports, at any depth."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("test_"):
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("test_"))
    return found


def test_no_test_module_imports_another():
    found = {(path.stem, imported) for path in sorted((ROOT / "tests").rglob("*.py"))
             for imported in imported_test_modules(path.read_text())}
    assert found == set(), "put a shared model in tests/sample_models.py, a shared check in tests/checks.py"


def test_the_finder_sees_both_forms_of_import():
    assert imported_test_modules("from test_a import X\ndef f():\n    import test_b\n") == {"test_a", "test_b"}

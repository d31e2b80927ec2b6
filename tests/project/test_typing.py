"""mypy over symkin/ (issue 19: a typed package): clean, without blanket ignores.

The check landed on 2026-11-25 as a ratchet of 197 errors in 55 modules and was driven to zero
the same day (Optional values narrowed where they are used, properties that raise a clear error
instead of returning None, typed generated-function helpers and protocols).  Now any error fails,
as does an ignore comment that silences no error (``warn_unused_ignores`` in pyproject.toml's
[tool.mypy]) or names no error code (a blanket ``# type: ignore`` would hide every error of its
line).  Third-party packages without type information are imported as Any; nothing of symkin is
excluded.
"""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from conftest import ROOT

pytest.importorskip("mypy")

#: An ignore comment without an error code: ``# type: ignore`` not followed by ``[code]``.
BLANKET_IGNORE = re.compile(r"#\s*type:\s*ignore(?!\[)")


def test_mypy_is_clean(tmp_path):
    result = subprocess.run([sys.executable, "-m", "mypy", "symkin", "--cache-dir", str(tmp_path / "cache")],
                            cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Success: no issues found" in result.stdout


def test_no_blanket_type_ignores():
    found = [f"{path.relative_to(ROOT)}:{k}" for path in sorted((ROOT / "symkin").rglob("*.py"))
             for k, line in enumerate(path.read_text().splitlines(), 1) if BLANKET_IGNORE.search(line)]
    assert not found, f"ignore comments without an error code: {found}"


def test_the_blanket_pattern_tells_them_apart():
    assert BLANKET_IGNORE.search("x = f()  # type: ignore")
    assert BLANKET_IGNORE.search("y  #type:ignore  ")
    assert not BLANKET_IGNORE.search("x = f()  # type: ignore[attr-defined]")

"""Documentation is code (issue 16): every fenced ``python`` and ``sh`` block of README.md and docs/*.md runs.

The blocks run in a scratch directory that holds copies of the repository's ``models/`` and
``generated/`` (so a block may derive into ``generated/`` or write ``out/`` without touching
the checkout) and a link to its ``.venv``; ``sh`` blocks run under ``bash -euo pipefail`` with
the test's Python environment first on PATH; the blocks of one file run in order (the
``python`` ones in one namespace), as a reader follows them in one session.  A python expression line whose
comment quotes its result (``analysis.gci(arm).value  # 0.2233408989620131 +- 4e-15``) is
checked: the value must round to the quoted digits, within the quoted error bar.  A block that is deliberately not run
says so visibly: the line before it contains "Not run by the tests" and the reason.
"""

from __future__ import annotations

import ast
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT

DOCUMENTS = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
FENCE = re.compile(r"^```(python|sh)[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
NOT_RUN = "not run by the tests"


def blocks(path: Path) -> list[tuple[str, int, str, bool]]:
    """(language, line, code, runnable) of every python/sh block of a Markdown file."""
    text = path.read_text()
    found = []
    for match in FENCE.finditer(text):
        before = [line for line in text[:match.start()].splitlines() if line.strip()][-1:]
        runnable = not (before and NOT_RUN in before[0].lower())
        found.append((match.group(1), text[:match.start()].count("\n") + 1, match.group(2), runnable))
    return found


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    directory = tmp_path_factory.mktemp("docs")
    shutil.copytree(ROOT / "models", directory / "models")
    shutil.copytree(ROOT / "generated", directory / "generated")
    (directory / ".venv").symlink_to(Path(sys.prefix))  # README's commands say .venv/bin/symkin
    return directory


def _environment() -> dict[str, str]:
    return dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", MPLBACKEND="Agg",
                SYMKIN_QUIET="1")


#: A quoted result: an expression line whose comment starts with a number, optionally "+- error".
QUOTE = re.compile(r"#\s*(-?\d+(?:\.\d*)?(?:e[-+]?\d+)?)(?:\s*\+-\s*(\d+(?:\.\d*)?(?:e[-+]?\d+)?))?(?:\s|$)")


def quoted_values(code: str) -> dict[int, tuple[float, int, float]]:
    """{line in the block: (quoted number, its significant digits, its error bar or 0)} for the
    expression statements whose comment quotes a result, e.g. ``gci(...).value  # 0.22334 +- 4e-15``."""
    quotes = {}
    lines = code.splitlines()
    for node in ast.parse(code).body:
        if not isinstance(node, ast.Expr):
            continue
        match = QUOTE.search(lines[node.end_lineno - 1][node.end_col_offset:])  # the comment after the expression
        if match:
            mantissa = match.group(1).split("e")[0].lstrip("-").replace(".", "").lstrip("0")
            quotes[node.lineno] = (float(match.group(1)), max(len(mantissa), 1),
                                   float(match.group(2)) if match.group(2) else 0.0)
    return quotes


def quote_mismatches(code: str, values: dict[int, object]) -> list[tuple[int, float, object]]:
    """(line, quoted, value) of every quoted result the recorded ``values`` contradict: the quote is
    the value rounded to its printed digits, within its printed error bar (if any)."""
    mismatches = []
    for number, (quoted, digits, error_bar) in quoted_values(code).items():
        value = getattr(values[number], "value", values[number])
        # a quoted 0 has no digits to round to: it is exact, up to its error bar
        allowed = (0.5 * 10.0 ** (math.floor(math.log10(abs(quoted))) - digits + 1) if quoted else 0.0) + error_bar
        if not abs(float(value) - quoted) <= allowed:
            mismatches.append((number, quoted, value))
    return mismatches


def _recording(code: str) -> ast.Module:
    """The block with each quoted expression statement wrapped in ``__record__(line, expression)``."""
    tree = ast.parse(code)
    quoted = quoted_values(code)
    for node in tree.body:
        if isinstance(node, ast.Expr) and node.lineno in quoted:
            node.value = ast.Call(ast.Name("__record__", ast.Load()), [ast.Constant(node.lineno), node.value], [])
    return ast.fix_missing_locations(tree)


#: What the scratch directory holds besides what the documents write under out/.
CHECKOUT_ENTRIES = {"models", "generated", ".venv", "out"}
RUN_DOCUMENTS = [path for path in DOCUMENTS if any(runnable for _, _, _, runnable in blocks(path))]


@pytest.mark.parametrize("path", RUN_DOCUMENTS, ids=[str(p.relative_to(ROOT)) for p in RUN_DOCUMENTS])
def test_a_document_runs_as_written(workspace, path, monkeypatch):
    """The document's blocks in order: sh in a shell, python in one namespace, all in the same directory."""
    monkeypatch.chdir(workspace)
    monkeypatch.setenv("SYMKIN_QUIET", "1")
    monkeypatch.delenv("SYMKIN_C_ENTRY", raising=False)  # the C backend as a user gets it (conftest: ctypes)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict[str, object] = {"__name__": "__docs__"}
    before = {entry.name for entry in workspace.iterdir()}
    for language, line, code, runnable in blocks(path):
        where = f"{path.relative_to(ROOT)}:{line}"
        if not runnable:
            continue
        if language == "sh":
            run = subprocess.run(["bash", "-euo", "pipefail", "-c", code], cwd=workspace, env=_environment(),
                                 capture_output=True, text=True)
            assert run.returncode == 0, f"{where} exited {run.returncode}:\n{run.stderr[-3000:]}"
            continue
        values: dict[int, object] = {}
        namespace["__record__"] = lambda number, value: values.__setitem__(number, value) or value
        try:
            exec(compile(_recording(code), where, "exec"), namespace)
        except Exception as exc:  # noqa: BLE001 - report which block of which file failed
            pytest.fail(f"{where}: {type(exc).__name__}: {exc}")
        for number, quoted, value in quote_mismatches(code, values):
            pytest.fail(f"{path.relative_to(ROOT)}:{line + number}: the document quotes {quoted} but the code "
                        f"gives {value}")
    # issue 60: what a reader runs in the checkout writes under out/ (or generated/, what `make demo` refreshes)
    stray = sorted({entry.name for entry in workspace.iterdir()} - before - CHECKOUT_ENTRIES)
    assert not stray, f"{path.relative_to(ROOT)} writes {stray} into the checkout's root: write under out/"


def test_blocks_that_are_not_run_say_why():
    skipped = [(path, line) for path in DOCUMENTS for _, line, _, runnable in blocks(path) if not runnable]
    for path, line in skipped:
        before = path.read_text().splitlines()[:line - 1]
        reason = next(text for text in reversed(before) if text.strip())
        assert len(reason.strip()) > len(NOT_RUN) + 10, f"{path}:{line}: say why the block is not run"
    assert len(skipped) <= 2, skipped


def borrowed_imports(code: str, imported: set[str]) -> set[str]:
    """The names of ``imported`` (bound by earlier blocks' imports) that ``code`` uses without importing or
    assigning them."""
    own, bound, used = set(), set(), set()
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            own |= {alias.asname or alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.Name):
            (bound if isinstance(node.ctx, ast.Store) else used).add(node.id)
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            bound.add(node.name)
    return (used & imported) - own - bound


def test_each_python_block_imports_what_it_uses():
    """Issue 60: a reader copies one snippet, not the document - no block leans on an earlier block's imports."""
    borrowing = []
    for path in DOCUMENTS:
        imported: set[str] = set()
        for language, line, code, _ in blocks(path):
            if language != "python":
                continue
            missing = borrowed_imports(code, imported)
            if missing:
                borrowing.append(f"{path.relative_to(ROOT)}:{line}: imports {sorted(missing)} in an earlier block")
            imported |= {alias.asname or alias.name.split(".")[0] for node in ast.walk(ast.parse(code))
                         if isinstance(node, (ast.Import, ast.ImportFrom)) for alias in node.names}
    assert not borrowing, "\n".join(borrowing)
    assert borrowed_imports("x = np.zeros(3)\nimport math\nmath.pi", {"np", "math"}) == {"np"}  # the check bites


def test_a_quoted_result_that_the_code_does_not_give_is_caught():
    code = "x = 0.1 + 0.2\nx  # 0.30000000000000004\nx * 3  # 0.95 +- 0.01\n"
    values: dict[int, object] = {}
    namespace = {"__record__": lambda number, value: values.__setitem__(number, value) or value}
    exec(compile(_recording(code), "<doc>", "exec"), namespace)
    assert sorted(quoted_values(code)) == [2, 3]
    assert [(line, quoted) for line, quoted, _ in quote_mismatches(code, values)] == [(3, 0.95)]  # 0.9 is not 0.95 +- 0.01


def test_a_quoted_zero_is_exact():
    code = "x = 0.1 + 0.2 - 0.3\nx  # 0\nx - x  # 0\n"
    values: dict[int, object] = {}
    namespace = {"__record__": lambda number, value: values.__setitem__(number, value) or value}
    exec(compile(_recording(code), "<doc>", "exec"), namespace)
    assert [(line, quoted) for line, quoted, _ in quote_mismatches(code, values)] == [(2, 0.0)]  # 5.6e-17 is not 0


def test_the_documents_quote_results_that_are_checked():
    quotes = sum(len(quoted_values(code)) for path in DOCUMENTS for language, _, code, runnable in blocks(path)
                 if language == "python" and runnable)
    assert quotes >= 4

"""Hostile free text (issue 28): a model file's description, references, parameter docs and
names never become code in what symkin writes.  Each case of tests/hostile_text.py goes into every
free-text field of a model file; the derived numpy module imports, the JavaScript module loads
under Node.js and the C compiles warning-free, none runs a payload, and the text still reads in
their documentation.  The pages of ``symkin view``: tests/viewer/test_viewer_hostile.py."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hostile_text import NAME_CASES, TEXT_CASES, model_text
from symkin.backends.comments import block_comment, docstring, plain
from symkin.cli import main
from tolerances import KINEMATICS

ONLY = "fk,frames,jacobian"
JOINTS = [0.3, -0.2]


def _derive(path: Path, out: Path, capsys) -> tuple[int, str]:
    code = main(["derive", str(path), "-o", str(out), "--backend", "numpy,js,c", "--only", ONLY, "-q"])
    return code, capsys.readouterr().err


@pytest.fixture(scope="module")
def derived(tmp_path_factory) -> Path:
    """One directory per text case, derived from a model file holding the case in every free-text field."""
    root = tmp_path_factory.mktemp("hostile-code")
    for case, text in TEXT_CASES:
        path = root / f"{case}.yaml"
        path.write_text(model_text(text), encoding="utf-8")
        assert main(["derive", str(path), "-o", str(root / case), "--backend", "numpy,js,c", "--only", ONLY,
                     "-q"]) == 0, case
    return root


def _run(args: list[str], cwd: Path) -> str:
    run = subprocess.run(args, capture_output=True, text=True, cwd=cwd)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def _words(text: str) -> str:
    return " ".join(text.split())


def test_the_numpy_modules_import_and_run_no_payload(derived, tmp_path):
    """Each module imports in a fresh process (a payload would write ./pwned); its docstring reads the text."""
    script = ("import importlib.util, json, sys\n"
              "out = {}\n"
              "for case, path in json.loads(sys.argv[1]).items():\n"
              "    spec = importlib.util.spec_from_file_location('arm_' + case.replace('-', '_'), path)\n"
              "    module = importlib.util.module_from_spec(spec); spec.loader.exec_module(module)\n"
              f"    out[case] = [module.__doc__, module.fk.__doc__, module.fk({JOINTS}).tolist()]\n"
              "print(json.dumps(out))\n")
    paths = {case: str(derived / case / "arm" / "arm.py") for case, _ in TEXT_CASES}
    result = json.loads(_run([sys.executable, "-c", script, json.dumps(paths)], tmp_path))
    assert list(tmp_path.iterdir()) == [], "a payload ran"
    reference = None
    for case, text in TEXT_CASES:
        module_doc, fk_doc, fk = result[case]
        assert _words(plain(text)) in _words(module_doc), case
        assert _words(plain(text)) in _words(fk_doc), case  # the parameter's doc and unit
        reference = reference or fk
        np.testing.assert_allclose(fk, reference, rtol=0, atol=KINEMATICS)


def test_the_javascript_modules_load_and_run_no_payload(derived, tmp_path):
    script = ("const out = {};\n"
              "for (const [name, path] of Object.entries(JSON.parse(process.argv[1]))) {\n"
              "  const model = require(path);\n"
              f"  out[name] = model.fk({JOINTS});\n"
              "}\n"
              "out.markers = Object.getOwnPropertyNames(globalThis).filter((k) => k.startsWith('pwned'));\n"
              "console.log(JSON.stringify(out));\n")
    paths = {case: str(derived / case / "arm" / "arm.js") for case, _ in TEXT_CASES}
    result = json.loads(_run(["node", "-e", script, json.dumps(paths)], tmp_path))
    assert result.pop("markers") == []
    for case, text in TEXT_CASES:
        source = (derived / case / "arm" / "arm.js").read_text(encoding="utf-8")
        assert block_comment(text)[:60] in source, case
        assert "</" not in source.lower().replace("<\\/", ""), case
        assert "<!--" not in source, case
        np.testing.assert_allclose(result[case], result[TEXT_CASES[0][0]], rtol=0, atol=KINEMATICS)


def test_the_c_sources_compile_without_warnings(derived, tmp_path):
    sources = [str(derived / case / "arm" / "arm.c") for case, _ in TEXT_CASES]
    _run(["gcc", "-std=c99", "-fsyntax-only", "-Wall", "-Wextra", "-Werror", *sources], tmp_path)


@pytest.mark.parametrize("line", [text for _, text in TEXT_CASES] + ["a */ b /* c", '""""', 'x"', "\\"])
def test_comment_text_cannot_leave_its_comment(line):
    """The escapes themselves, on every case: a docstring line parses back to the plain text; a block
    comment line holds no comment or script delimiter."""
    assert ast.literal_eval('"""' + docstring(line) + '\n"""') == plain(line) + "\n"
    comment = block_comment(line)
    assert "*/" not in comment
    assert "/*" not in comment
    assert "</" not in comment
    assert "<!--" not in comment
    assert not any(c in comment for c in "\n\r\u2028\u2029\u202e")


@pytest.mark.parametrize("case,name", NAME_CASES, ids=[c for c, _ in NAME_CASES])
def test_hostile_names_are_used_as_names_or_refused_where_they_stand(case, name, tmp_path, capsys):
    path = tmp_path / "model.yaml"
    path.write_text(model_text("a planar arm", parameter=name), encoding="utf-8")
    code, err = _derive(path, tmp_path / "out", capsys)
    if code == 2:
        assert f"{path}:" in err, err
        assert "fix:" in err, err
        assert "Traceback" not in err, err
        assert not (tmp_path / "out").exists(), "nothing half-written"
        return
    assert code == 0, err
    # a name like an Object.prototype member still takes its default when a call leaves it out
    script = (f"const m = require({json.dumps(str(tmp_path / 'out' / 'arm' / 'arm.js'))});\n"
              f"console.log(JSON.stringify([m.fk({JOINTS}), m.fk({JOINTS}, {{{json.dumps(name)}: 0.1}})]));")
    default, given = json.loads(_run(["node", "-e", script], tmp_path))
    np.testing.assert_allclose(default, given, rtol=0, atol=KINEMATICS)

"""The hostile-input corpus and bounded fuzzing: every bad model gives a located error, exit code 2,
writes nothing and runs nothing (each case runs in an empty directory that must stay empty; code
payloads would create ./pwned)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from conftest import SYMKIN_CLI
from fuzz_strategies import hostile_models
from symkin.cli import main
from symkin.errors import ModelError
from symkin.model import model_from_text
from symkin.model.yaml_source import MAX_FILE_BYTES

CORPUS = Path(__file__).resolve().parents[1] / "corpus" / "hostile"
MANIFEST = json.loads((CORPUS / "manifest.json").read_text())


def test_the_corpus_is_complete():
    assert len(MANIFEST) >= 50
    assert sorted(p.name for p in CORPUS.glob("*.yaml")) == sorted(c["file"] for c in MANIFEST)
    fuzzed = [c for c in MANIFEST if "-fuzz-" in c["file"]]
    assert len(fuzzed) >= 10


def _run(args: list[str], workdir: Path, monkeypatch, capsys) -> tuple[int, str]:
    monkeypatch.chdir(workdir)
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("case", MANIFEST, ids=[c["file"][:-5] for c in MANIFEST])
def test_hostile_model_is_refused_with_a_located_message(case, tmp_path, monkeypatch, capsys):
    path = CORPUS / case["file"]
    workdir = tmp_path / "work"
    workdir.mkdir()
    for command in (["derive", str(path), "-o", "out"], ["check", str(path)]):
        code, err = _run(command, workdir, monkeypatch, capsys)
        assert code == 2, err
        assert case["expect"] in err, err[:2000]
        location = f"{path}:{case['line']}:" if case["line"] else str(path)
        assert location in err, err[:2000]
        assert "fix:" in err
        assert "Traceback" not in err
        assert len(err) < 5000, "messages echo bounded excerpts of the input, not the input"
        assert list(workdir.iterdir()) == [], "nothing written, nothing executed"


@pytest.mark.parametrize("name", ["exec-python-object-apply", "exec-dunder-import", "exec-python-object-new"])
def test_code_payloads_do_not_run_in_a_fresh_process(name, tmp_path):
    (case,) = [c for c in MANIFEST if c["file"][4:-5] == name]
    result = subprocess.run(SYMKIN_CLI + ["derive", str(CORPUS / case["file"]), "-o", "out"], capture_output=True,
                            text=True, cwd=tmp_path)
    assert result.returncode == 2
    assert case["expect"] in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_file_over_the_size_limit_is_refused_unread(tmp_path, monkeypatch, capsys):
    path = tmp_path / "big.yaml"
    path.write_text("name: arm\ndescription: '" + "x" * MAX_FILE_BYTES + "'\n")
    (tmp_path / "work").mkdir()
    code, err = _run(["derive", str(path), "-o", "out"], tmp_path / "work", monkeypatch, capsys)
    assert code == 2
    assert "more than the limit" in err
    assert str(path) in err
    assert list((tmp_path / "work").iterdir()) == []


@settings(max_examples=150, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(hostile_models)
def test_fuzzed_models_load_or_fail_with_a_model_error(text):
    try:
        model_from_text(text, "arm", "fuzz.yaml")
    except ModelError as err:
        for problem in err.problems:
            assert problem.message
            assert problem.fix
            assert problem.file == "fuzz.yaml"


@settings(max_examples=25, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(hostile_models)
def test_fuzzed_models_through_the_cli_exit_0_or_2_and_write_nothing_on_error(tmp_path_factory, text):
    base = tmp_path_factory.mktemp("fuzz")
    path = base / "arm.yaml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    code = main(["derive", str(path), "-o", str(base / "out"), "-q"])
    assert code in (0, 2)
    if code == 2:
        assert not (base / "out").exists()
    else:
        assert (base / "out").is_dir()
    assert not (base / "pwned").exists()


def test_deep_block_nesting_is_refused_with_a_location(tmp_path, monkeypatch, capsys):
    text = "name: arm\ndescription:\n" + "".join(" " * (i + 1) + "a:\n" for i in range(700)) + " " * 701 + "1\n"
    path = tmp_path / "deep.yaml"
    path.write_text(text)
    (tmp_path / "work").mkdir()
    code, err = _run(["check", str(path)], tmp_path / "work", monkeypatch, capsys)
    assert code == 2
    assert "nested deeper than 64 levels" in err
    assert f"{path}:" in err

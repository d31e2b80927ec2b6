"""Issue 34: the derivation cache (symkin.pipeline_cache) - a repeated derive of an unchanged model copies its files.

References: a fresh derive (--no-cache) for the bytes of a hit; the key's inputs changed one at a time for the
misses; entries damaged on disk (a flipped byte, a missing file, a torn entry.json) for the rebuilds; two derives
started together for the concurrency; the interpreter's module table for "a hit imports no sympy".
"""

from __future__ import annotations

import filecmp
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import pipeline_cache

#: A quick derivation of the 2R arm (two outputs, numpy only).
REQUEST = ["--only", "fk,jacobian", "--backend", "numpy"]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache directory of the test's own, for this process and the commands it runs."""
    directory = tmp_path / "cache"
    monkeypatch.setenv("SYMKIN_CACHE_DIR", str(directory))
    return directory


def derive(model: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    result = subprocess.run(SYMKIN_CLI + ["derive", str(model), "-o", str(out), *REQUEST, *extra],
                            capture_output=True, text=True, env=os.environ)
    assert result.returncode == 0, result.stderr
    return result


def same_tree(a: Path, b: Path) -> bool:
    compared = filecmp.dircmp(a, b)
    names = compared.common_files
    match, mismatch, errors = filecmp.cmpfiles(a, b, names, shallow=False)
    return (not compared.left_only and not compared.right_only and not mismatch and not errors
            and all(same_tree(a / d, b / d) for d in compared.common_dirs))


def entries(cache: Path) -> list[Path]:
    return sorted(p for p in (cache / "derivations").iterdir() if not p.name.startswith("."))


def test_a_repeated_derive_is_a_byte_identical_hit_that_imports_no_sympy(cache, tmp_path):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    first = derive(model, tmp_path / "first")
    assert "unchanged since a derivation kept in the cache" not in first.stdout
    assert len(entries(cache)) == 1
    probe = ("import sys; from symkin.cli import main; code = main(sys.argv[1:]); "
             "print('sympy' in sys.modules, 'symengine' in sys.modules); sys.exit(code)")
    hit = subprocess.run([sys.executable, "-c", probe, "derive", str(model), "-o", str(tmp_path / "hit"), *REQUEST],
                         capture_output=True, text=True, env=os.environ)
    assert hit.returncode == 0, hit.stderr
    assert "unchanged since a derivation kept in the cache" in hit.stdout
    assert hit.stdout.strip().endswith("False False")                  # neither sympy nor symengine imported
    fresh = derive(model, tmp_path / "fresh", "--no-cache")
    assert "unchanged" not in fresh.stdout
    assert same_tree(tmp_path / "hit" / "planar_2r", tmp_path / "fresh" / "planar_2r")
    assert len(entries(cache)) == 1                                     # --no-cache kept nothing new


def test_a_changed_model_request_or_version_misses(cache, tmp_path, monkeypatch):
    model = tmp_path / "arm.yaml"
    text = (MODELS_DIR / "planar_2r.yaml").read_text()
    model.write_text(text)
    key = pipeline_cache.request_key(model, {"only": "fk"})
    assert key == pipeline_cache.request_key(model, {"only": "fk"})
    assert key != pipeline_cache.request_key(model, {"only": "fk,jacobian"})       # the request
    renamed = tmp_path / "other.yaml"
    renamed.write_text(text)
    assert key != pipeline_cache.request_key(renamed, {"only": "fk"})              # the name the manifest records
    model.write_text(text.replace("l1: {value: 0.1,", "l1: {value: 0.2,"))
    assert key != pipeline_cache.request_key(model, {"only": "fk"})                # the model's content
    model.write_text(text)
    monkeypatch.setattr(pipeline_cache, "code_digest", lambda: "another symkin or sympy")
    assert key != pipeline_cache.request_key(model, {"only": "fk"})                # the code and versions
    including = tmp_path / "arm.urdf.xacro"
    including.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:include filename="a.xacro"/>'
                         "</robot>")
    assert pipeline_cache.request_key(including, {}) is None                       # its inputs are not all in it


@pytest.mark.parametrize("damage", ["flipped byte", "missing file", "torn entry.json"])
def test_a_damaged_entry_is_detected_and_derived_again(cache, tmp_path, damage):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    derive(model, tmp_path / "first")
    (entry,) = entries(cache)
    files = sorted(p for p in (entry / "files").rglob("*") if p.is_file())
    if damage == "flipped byte":
        data = bytearray(files[0].read_bytes())
        data[len(data) // 2] ^= 1
        files[0].write_bytes(bytes(data))
    elif damage == "missing file":
        files[-1].unlink()
    else:
        text = (entry / "entry.json").read_text()
        (entry / "entry.json").write_text(text[:len(text) // 2])
    again = derive(model, tmp_path / "again")
    assert "unchanged" not in again.stdout                              # derived, not copied
    assert same_tree(tmp_path / "first" / "planar_2r", tmp_path / "again" / "planar_2r")
    (rebuilt,) = entries(cache)
    assert json.loads((rebuilt / "entry.json").read_text())["model"] == "planar_2r"
    assert "unchanged" in derive(model, tmp_path / "third").stdout


def test_two_concurrent_derives_of_one_model_both_succeed(cache, tmp_path):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    runs = [subprocess.Popen(SYMKIN_CLI + ["derive", str(model), "-o", str(tmp_path / f"out{k}"), *REQUEST, "-q"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=os.environ)
            for k in range(2)]
    for run in runs:
        _, err = run.communicate(timeout=300)
        assert run.returncode == 0, err
    assert same_tree(tmp_path / "out0" / "planar_2r", tmp_path / "out1" / "planar_2r")
    assert len(entries(cache)) == 1
    assert not [p for p in (cache / "derivations").iterdir() if p.name.startswith(".")]  # no staging left


def test_analysis_commands_reuse_the_cache_and_cache_clear_empties_it(cache, tmp_path):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    command = SYMKIN_CLI + ["gci", str(model), "-n", "200"]
    for _ in range(2):
        result = subprocess.run(command, capture_output=True, text=True, env=os.environ)
        assert result.returncode == 0, result.stderr
    (entry,) = entries(cache)
    assert json.loads((entry / "entry.json").read_text())["model"] == "planar_2r"
    listing = subprocess.run(SYMKIN_CLI + ["cache", "list"], capture_output=True, text=True, env=os.environ)
    assert entry.name in listing.stdout
    cleared = subprocess.run(SYMKIN_CLI + ["cache", "clear", "--kind", "derivations"], capture_output=True,
                             text=True, env=os.environ)
    assert "removed 1 derivation" in cleared.stdout
    assert entries(cache) == []

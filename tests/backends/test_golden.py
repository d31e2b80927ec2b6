"""generated/ is exactly what `symkin derive` produces now (update with `make generate`)."""

from __future__ import annotations

import filecmp
import importlib.util
import os
import random
import subprocess
from pathlib import Path

from conftest import EXAMPLE_MODELS, GENERATED_DIR, MODELS_DIR, SYMKIN_CLI


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_symengine_is_not_shadowed_by_symforce():
    """SymForce installs its own fork of symengine's wrapper inside the ``symengine`` package.

    That fork orders CSE output differently, so a venv holding it regenerates generated/ with
    other (equally correct) bytes.  Benchmarks that need SymForce run in .venv-bench instead.
    """
    assert importlib.util.find_spec("symforce") is None, (
        "symforce is installed in this venv and shadows symengine's wrapper; generated code would "
        "differ from generated/. Fix: `pip uninstall symforce symforce-sym && pip install --force-reinstall "
        "--no-deps -c requirements/constraints.txt symengine`, and run `make bench` (it uses .venv-bench)."
    )


def test_generated_directory_holds_exactly_the_example_models():
    assert sorted(p.name for p in GENERATED_DIR.iterdir() if p.is_dir()) == EXAMPLE_MODELS


def test_regenerating_gives_byte_identical_files(tmp_path):
    """Run the CLI in a fresh process with a random hash seed (a new one each run, named in the message to
    reproduce a failure) and diff the trees: the tests read the committed files (conftest ``generated_dir``)."""
    hash_seed = str(random.SystemRandom().randrange(1, 2 ** 32))
    env = dict(os.environ, PYTHONHASHSEED=hash_seed)
    models = [str(MODELS_DIR / f"{name}.yaml") for name in EXAMPLE_MODELS]
    subprocess.run(SYMKIN_CLI + ["derive", *models, "-o", str(tmp_path), "--quiet"], check=True, env=env)
    fresh, committed = _tree(tmp_path), _tree(GENERATED_DIR)
    assert sorted(fresh) == sorted(committed), \
        f"file lists differ (PYTHONHASHSEED={hash_seed}): run `make generate` and commit generated/"
    changed = [name for name in fresh if fresh[name] != committed[name]]
    assert not changed, \
        f"regenerated files differ (PYTHONHASHSEED={hash_seed}): {changed}; run `make generate` and commit generated/"
    assert not filecmp.dircmp(tmp_path, GENERATED_DIR).diff_files

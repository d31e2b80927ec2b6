"""The package installs from a wheel with its templates, and the wheel lists every subpackage."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from conftest import MODELS_DIR, ROOT


def _listed_packages() -> set[str]:
    text = (ROOT / "pyproject.toml").read_text()
    block = re.search(r"packages = \[(.*?)\]", text, re.S).group(1)
    return set(re.findall(r'"([\w.]+)"', block))


def test_every_package_directory_is_listed_in_pyproject():
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "symkin").rglob("__init__.py")}
    found |= {"symkin.templates." + ".".join(p.relative_to(ROOT / "templates").parts)
              for p in (ROOT / "templates").iterdir() if p.is_dir() and p.name != "__pycache__"}
    found.add("symkin.templates")
    assert found == _listed_packages()


@pytest.mark.slow
def test_wheel_installs_in_a_fresh_venv_and_derives_a_model(tmp_path):
    wheel_dir = tmp_path / "wheel"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--quiet",
                    "-w", str(wheel_dir), str(ROOT)], check=True)
    (wheel,) = wheel_dir.glob("symkin-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "symkin/templates/numpy/module.py.j2" in names
    assert "symkin/py.typed" in names  # a typed package (PEP 561)
    assert "symkin/templates/c/header.h.j2" in names
    assert "symkin/templates/c/source.c.j2" in names
    assert "symkin/templates/js/module.js.j2" in names
    assert "symkin/backends/casadi/emit.py" in names
    assert "symkin/cli/__init__.py" in names

    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", "--quiet", str(wheel)], check=True)
    # The dependencies come from the test environment (no network needed): a .pth file adds its site-packages.
    fresh_site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                capture_output=True, text=True, check=True).stdout.strip()
    (Path(fresh_site) / "symkin_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")

    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    where = subprocess.run([str(python), "-c", "import symkin.templates as t, symkin; print(t.__file__); "
                                               "print(symkin.__file__)"],
                           capture_output=True, text=True, check=True, cwd=work, env=env).stdout.split()
    assert all(str(venv) in w for w in where), where
    subprocess.run([str(venv / "bin" / "symkin"), "derive", str(MODELS_DIR / "planar_2r.yaml"), "-o", "out", "-q"],
                   check=True, cwd=work, env=env)
    value = subprocess.run([str(python), "-c", "from symkin import load; print(load('out/planar_2r').fk([0, 0])[0, 3])"],
                           capture_output=True, text=True, check=True, cwd=work, env=env).stdout
    assert float(value) == pytest.approx(0.2)

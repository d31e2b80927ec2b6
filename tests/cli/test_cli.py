"""The command line: help everywhere, summary output, exit codes."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from conftest import GENERATED_DIR, MODELS_DIR, ROOT, SYMKIN_CLI
from symkin.cli import build_parser


def _commands() -> list[str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sorted(sub.choices)


@pytest.mark.parametrize("command", [[]] + [[c] for c in _commands()])
def test_every_command_has_help(command):
    result = subprocess.run(SYMKIN_CLI + command + ["--help"], capture_output=True, text=True)
    assert result.returncode == 0
    assert "usage: symkin" in result.stdout
    # argparse %-formats help strings but prints descriptions as written: an escaped %% there shows
    assert "%%" not in result.stdout
    assert "%(" not in result.stdout


#: Commands on generated code, run with sympy made unimportable: the CLI imports the symbolic side only for
#: the commands that read a model file (issue 34: ``symkin --help`` and numeric commands start in ~0.2 s).
NUMERIC_COMMANDS = (["--help"], ["gci", "--help"], ["gci", str(GENERATED_DIR / "delta"), "-n", "64"],
                    ["workspace", str(GENERATED_DIR / "planar_2r"), "-n", "64"],
                    ["rate", str(GENERATED_DIR / "planar_2r"), "-n", "16", "--no-figure"])


#: What the parser of every command may not import (issue 34: ``symkin --help`` at most 0.15 s more than importing
#: numpy, benchmarks/bench_startup.py): the libraries a command imports when it runs.
HEAVY_MODULES = ("sympy", "symengine", "casadi", "scipy", "matplotlib", "jinja2", "yaml", "dask", "mpmath",
                 "symkin.numerics.conditioning", "symkin.design.formulation", "symkin.model")


def test_the_parser_imports_no_heavy_library():
    script = ("import sys\n"
              "from symkin.cli import build_parser\n"
              "build_parser()\n"
              f"print(sorted(name for name in {HEAVY_MODULES!r} if name in sys.modules))\n")
    result = subprocess.run([SYMKIN_CLI[0], "-c", script], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]", result.stdout


def test_help_and_numeric_commands_import_no_sympy(tmp_path):
    script = ("import sys; sys.modules['sympy'] = None\n"
              "from symkin.cli import main\n"
              f"for argv in {NUMERIC_COMMANDS!r}:\n"
              "    try:\n"
              "        code = main(argv)\n"
              "    except SystemExit as exit:\n"
              "        code = exit.code\n"
              "    assert code == 0, (argv, code)\n")
    result = subprocess.run([SYMKIN_CLI[0], "-c", script], capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr


def test_derive_prints_a_summary_table(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "planar_2r.yaml"), "-o", str(tmp_path), "--no-cache"],
                            capture_output=True, text=True, check=True)
    assert "planar_2r: 2 DoF" in result.stdout
    assert "ops derived -> cse" in result.stdout
    assert "jacobian" in result.stdout
    assert (tmp_path / "planar_2r" / "manifest.json").exists()


def test_check_validates_and_writes_nothing(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["check", str(MODELS_DIR / "ur10e.yaml")], capture_output=True, text=True,
                            check=True, cwd=tmp_path)
    assert "ok - model 'ur10e', 6 joints" in result.stdout
    assert list(tmp_path.iterdir()) == []


def test_a_reader_that_closes_the_pipe_ends_the_command_quietly():
    """'symkin check models/*.yaml | head -1': stdout closed before symkin writes; no BrokenPipeError traceback,
    the exit code of a command killed by SIGPIPE (128 + 13)."""
    process = subprocess.Popen([*SYMKIN_CLI, "check", *map(str, sorted(MODELS_DIR.glob("*.yaml")))],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()  # before the interpreter has started: every write of symkin's finds no reader
    _, err = process.communicate(timeout=120)
    assert b"Traceback" not in err, err
    assert b"BrokenPipe" not in err, err
    assert process.returncode == 141


def test_quantities_lists_the_outputs():
    result = subprocess.run(SYMKIN_CLI + ["quantities"], capture_output=True, text=True, check=True)
    for name in ("fk", "frames", "jacobian", "jacobian_geometric", "task_coordinates"):
        assert name in result.stdout


def test_library_derive_matches_the_cli(tmp_path):
    import symkin

    path = symkin.derive(MODELS_DIR / "planar_2r.yaml", tmp_path, outputs=["fk"])
    assert symkin.load(path).fk([0.0, 0.0])[0, 3] == pytest.approx(0.2)


def test_ci_runs_exactly_the_readme_test_command():
    """.ci/run is what CI executes; it must run the README's `make test` line, word for word."""
    readme = [line for line in (ROOT / "README.md").read_text().splitlines() if line.startswith("make test")]
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line.startswith("make ")]
    assert len(readme) == 1, (readme, ci)
    assert ci == readme, (readme, ci)


def test_negative_values_with_units_are_values_not_options():
    """Issue 16: ``--q0 0 30deg 0 -60deg`` was refused (argparse read -60deg as an option)."""
    from symkin.cli import build_parser

    args = build_parser().parse_args(["simulate", "generated/ur10e", "--q0", "0", "30deg", "0", "-60deg", "-1e-3",
                                      "-.5", "--scenario", "sine"])
    assert args.q0 == ["0", "30deg", "0", "-60deg", "-1e-3", "-.5"]
    assert args.scenario == "sine"
    with pytest.raises(SystemExit):  # an unknown option is still an error
        build_parser().parse_args(["simulate", "generated/ur10e", "--q0", "0", "-x"])


def test_the_command_runs_blas_on_one_thread_unless_the_user_says_otherwise():
    """symkin.cli.BLAS_THREADS: set before numpy is imported (importing the package imports no numpy), kept where the
    user set it."""
    probe = ("import sys, os, symkin; assert 'numpy' not in sys.modules; import symkin.cli, numpy; "
             "print(os.environ['OPENBLAS_NUM_THREADS'], os.environ['MKL_NUM_THREADS'])")
    bare = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    for given, printed in (({}, "1 1"), ({"OPENBLAS_NUM_THREADS": "4"}, "4 1")):
        result = subprocess.run([sys.executable, "-c", probe], env={**bare, **given}, capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        assert result.stdout.split() == printed.split()

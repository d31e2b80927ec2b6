"""Issue 62's ratchet: which modules above the run-time layer name the kind of a mechanism or its machinery.

The goal of issue 62 is one run-time mechanism that every analysis is written against once: at most
:data:`TARGET` modules of analysis/, cli/, simulation/, design/, viewer/ and stability/ (or their successors) may
still name what kind a mechanism is (serial, parallel, legs, the closure, a hybrid device's wrist, a platform).
A module names it where one of its identifiers does (names, attributes, definitions, arguments, keywords and
imports; not its strings or comments), by the words of :data:`KIND_WORDS`.

:data:`KNOWN` lists the modules that do today.  The test fails on a module that starts to (write it against
the mechanism instead) and on a listed one that no longer does (take it off the list): each step of the redesign
shortens it, until it is no longer than :data:`TARGET`.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator

from conftest import ROOT

#: The folders above the run-time layer whose modules should not tell mechanisms apart.
FOLDERS = ("analysis", "integration", "rating", "cli", "simulation", "design", "identification", "references", "viewer",
           "stability")
#: Words of an identifier (case-insensitive) that name a kind of mechanism or its machinery.
KIND_WORDS = re.compile(r"parallel|closure|wrist|(^|_)legs?($|_)|mechanismkind|kind_of|is_serial|(^|_)serial($|_)"
                        r"|hybrid|platform")
#: Identifiers that match the words but name no kind of mechanism: the UR family's spherical wrist is a serial
#: arm's closed-form inverse kinematics, not a hybrid device's wrist.
NOT_A_KIND = {"_ur_wrist"}
#: Issue 62's goal.
TARGET = 10
#: The modules that name a mechanism's kind today (the ratchet: this list only shrinks).
KNOWN = {
    "analysis/model_files.py", "analysis/needs.py",
    "cli/structure_cmd.py",
    "identification/closure_excitation.py", "identification/excitation.py", "identification/identified_model.py",
    "viewer/page.py",
    "stability/harness.py", "stability/states.py",
}


def identifiers(tree: ast.AST) -> Iterator[str]:
    """Every identifier of a module: names, attributes, definitions, arguments, keywords and imported names."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            yield node.id
        elif isinstance(node, ast.Attribute):
            yield node.attr
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            yield node.name
        elif isinstance(node, ast.arg):
            yield node.arg
        elif isinstance(node, ast.keyword) and node.arg:
            yield node.arg
        elif isinstance(node, ast.ImportFrom):
            yield node.module or ""
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)


def kind_names(text: str) -> set[str]:
    """The identifiers of a module's source that name a kind of mechanism."""
    return {name for name in identifiers(ast.parse(text))
            if name not in NOT_A_KIND and KIND_WORDS.search(name.lower())}


def naming_modules() -> dict[str, set[str]]:
    """{module path under symkin/: the kind names it uses} for the modules of :data:`FOLDERS` that use any."""
    found = {}
    for folder in FOLDERS:
        for path in sorted((ROOT / "symkin" / folder).rglob("*.py")):
            names = kind_names(path.read_text())
            if names:
                found[path.relative_to(ROOT / "symkin").as_posix()] = names
    return found


def test_no_new_module_tells_mechanisms_apart_and_the_list_only_shrinks():
    found = naming_modules()
    new = {module: sorted(found[module])[:5] for module in set(found) - KNOWN}
    assert not new, f"write these against the run-time mechanism instead of naming its kind (issue 62): {new}"
    gone = sorted(KNOWN - set(found))
    assert not gone, f"these no longer name a mechanism's kind: take them off KNOWN in this test: {gone}"


def test_the_goal_is_held():
    """Issue 62's goal, reached: no more than TARGET modules above the run-time layer name a mechanism's kind."""
    assert len(KNOWN) <= TARGET


def test_the_words_find_what_they_should():
    """The detector itself: identifiers count, strings and comments do not, and the serial IK's wrist is no kind."""
    assert kind_names("from symkin.mechanism import MechanismKind\n") >= {"MechanismKind"}
    assert kind_names("def f(model):\n    return model.info.is_parallel\n") == {"is_parallel"}
    assert kind_names("x = closure_workspace(model, legs=2)\n") == {"closure_workspace", "legs"}
    assert kind_names("text = 'parallel legs'  # a closure\n") == set()
    assert kind_names("def _ur_wrist(q):\n    return q\n") == set()
    assert kind_names("serial_jacobian = 1\nserials = 2\nleg_dof = 3\nlegend = 4\n") == {"serial_jacobian", "leg_dof"}


#: The packages of the derivation layer, which a thin CLI reaches through the library (issue 62: "cli/ no longer
#: imports derivation or parallel").
DERIVING = ("symkin.derivation", "symkin.parallel", "symkin.kinematics", "symkin.dynamics")
#: The CLI modules that import them (the ratchet reached empty: a command that needs a derivation calls
#: symkin.pipeline, symkin.api or symkin.analysis.model_files).
KNOWN_DERIVING_CLI: dict[str, set[str]] = {}


def deriving_imports(text: str) -> set[str]:
    """The derivation-layer packages a module imports (at module level or inside functions)."""
    modules = set()
    for node in ast.walk(ast.parse(text)):
        names = [node.module or ""] if isinstance(node, ast.ImportFrom) else \
            [alias.name for alias in node.names] if isinstance(node, ast.Import) else []
        modules |= {package for name in names for package in DERIVING if name == package or
                    name.startswith(package + ".")}
    return modules


def test_the_cli_reaches_the_derivation_only_through_the_library():
    found = {path.relative_to(ROOT / "symkin").as_posix(): deriving_imports(path.read_text())
             for path in sorted((ROOT / "symkin" / "cli").rglob("*.py"))}
    found = {module: packages for module, packages in found.items() if packages}
    grown = {module: sorted(packages - KNOWN_DERIVING_CLI.get(module, set())) for module, packages in found.items()
             if packages - KNOWN_DERIVING_CLI.get(module, set())}
    assert not grown, f"call the library (symkin.api, symkin.pipeline) instead of the derivation layer: {grown}"
    shrunk = {module: sorted(packages - found.get(module, set())) for module, packages in KNOWN_DERIVING_CLI.items()
              if packages - found.get(module, set())}
    assert not shrunk, f"these imports are gone: take them off KNOWN_DERIVING_CLI in this test: {shrunk}"


def test_the_library_derive_refuses_what_symkin_derive_refuses(tmp_path):
    """Issue 62: the checks before a derivation live in the library (symkin.pipeline.require_derivable), so
    symkin.derive refuses a parallel model whose legs contradict its declared motion as the command does."""
    import pytest

    from sample_models import dual_scara_text
    from symkin import derive
    from symkin.errors import ModelError
    from symkin.model import model_from_text

    wrong = model_from_text(dual_scara_text().replace("motion: schoenflies", "motion: [x, y, z, roll]"), "scara")
    with pytest.raises(ModelError, match="do not let the platform move in its coordinate roll"):
        derive(wrong, tmp_path / "out", outputs=["closure"])
    assert not (tmp_path / "out").exists()

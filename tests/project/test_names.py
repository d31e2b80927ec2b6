"""One meaning per name (issue 35): a public top-level function or class of symkin is defined in one module.

A name defined in several modules is listed below with why: a convention every module of a kind follows (each
CLI command has ``register`` and ``run``), the same quantity or operation in another algebra or algorithm, or a
name that still has two meanings and waits for its rename (a ratchet: the list only shrinks).  A new name defined
twice fails here until it is renamed or listed.
"""

from __future__ import annotations

import ast
import collections

from conftest import ROOT

#: Convention: the same role in every module of a kind.
CONVENTIONS = {
    "register": "each CLI command module adds its parser (symkin/cli/*_cmd.py)",
    "run": "each CLI command module's entry point",
    "load": "typing.overload signatures of runtime.loader.load; viewer.notebook.load is that load returning the "
            "notebook's model class",
}
#: The same meaning in another algebra, algorithm or view.
SAME_MEANING = {
    "mass_matrix": "M(q) by Lagrange's equations (dynamics.lagrange) and by the composite rigid body of "
                   "Newton-Euler (dynamics.newton_euler)",
    "cross": "the cross product on symengine lists (dynamics.program) and on numpy arrays (ik.rotations)",
    "dot": "the dot product on symengine lists (dynamics.program) and on numpy arrays (ik.subproblems)",
    "rotation_matrix": "R(axis, angle) in sympy (geometry) and in numpy (ik.rotations)",
    "Parameter": "a model parameter in the schema and as the manifest records it (runtime.info)",
    "Coordinate": "a coordinate in the schema and as the manifest records it (runtime.info)",
    "determinant": "the determinant in sympy (parallel.determinant) and in CasADi (design.smooth)",
    "adjugate": "the adjugate in sympy (parallel.determinant) and in CasADi (design.smooth)",
    "inverse_frobenius": "1/kappa_F of square Jacobians in CasADi (design.smooth, by adj J) and in jax.numpy "
                         "(analysis.device_integrand, by (J^T J)^-1): the design surrogate's two programs",
    "angular_velocity_matrix": "E with omega = E d(roll, pitch, yaw)/dt in numpy (mechanism.reach) and in CasADi "
                               "(design.formulation)",
    "jacobian": "J of a parallel mechanism: the derived quantity (parallel.quantities) and its evaluation on a "
                "loaded model (analysis.mechanism)",
    "csv_text": "a result's CSV file: the datasheet's and the simulation's",
    "figure_png": "a result's figure: the datasheet's, the excitation's and the simulation's",
    "clear": "clearing a cache: the C build cache and the derivation cache",
}
#: Two meanings still: renamed one at a time (issue 35).
TO_RENAME: dict[str, str] = {}


def defined_names() -> dict[str, list[str]]:
    """Public top-level function and class names -> the modules that define them."""
    out = collections.defaultdict(list)
    for path in sorted((ROOT / "symkin").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and not node.name.startswith("_"):
                out[node.name].append(module)
    return out


def test_a_public_name_is_defined_in_one_module_or_says_why_not():
    repeated = {name: modules for name, modules in defined_names().items() if len(modules) > 1}
    unexplained = {name: modules for name, modules in repeated.items()
                   if name not in CONVENTIONS | SAME_MEANING | TO_RENAME}
    assert not unexplained, f"rename these or say why one name serves (tests/project/test_names.py): {unexplained}"


def test_the_lists_name_only_names_defined_twice():
    """A renamed name leaves the lists (the ratchet only shrinks)."""
    repeated = {name for name, modules in defined_names().items() if len(modules) > 1}
    stale = (set(CONVENTIONS) | set(SAME_MEANING) | set(TO_RENAME)) - repeated
    assert not stale, f"no longer defined twice: remove them from tests/project/test_names.py: {sorted(stale)}"


def test_the_names_the_review_found_with_two_meanings_have_one():
    """Issue 35's list: each of these is now defined once (and 'scene' names only the model file's section: the
    fused generated function is ``combined``, symkin.pipeline.COMBINED_FUNCTION)."""
    names = defined_names()
    for name in ("characteristic_length", "make_function", "integrate", "load_model", "Program", "home_pose"):
        assert len(names.get(name, [])) == 1, (name, names.get(name))


def imported_private_names(tree: ast.AST) -> list[tuple[str, str]]:
    """(symkin module, name) of every private name ``tree`` imports from a symkin module."""
    return [(node.module, a.name) for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("symkin")
            for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]


def private_imports() -> list[tuple[str, str, str]]:
    """(importing module, imported module, name) of every import of another symkin module's private name."""
    found = []
    for path in sorted((ROOT / "symkin").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        found += [(module, *pair) for pair in imported_private_names(ast.parse(path.read_text()))]
    return found


def test_no_module_imports_another_modules_private_name():
    """A name another module needs is public: the derivation graph's keys (the quantity functions other
    quantities depend on: ``parallel_structure``, ``reduced_legs``, ``newton_euler_links``...) and the helpers
    shared between quantity modules carry public names (issue 35: "the catalog's public keys are named
    _private")."""
    assert not private_imports()


def test_the_private_import_scan_sees_an_import():
    source = ("from symkin.parallel.quantities import _hidden, visible\n"
              "def f():\n    from symkin.dynamics import _late as late\n"
              "from numpy import _private_elsewhere\nfrom symkin import __version__\n")
    assert imported_private_names(ast.parse(source)) == [("symkin.parallel.quantities", "_hidden"),
                                                         ("symkin.dynamics", "_late")]

"""The derivation graph derives what is asked for and what it needs, nothing more."""

from __future__ import annotations

import ast
import inspect
import json
import subprocess
import types

import pytest
from conftest import MODELS_DIR, SYMKIN_CLI

from symkin import pipeline
from symkin.derivation import Derivation, catalog, emitted_quantities, quantity
from symkin.errors import DerivationError, ModelError
from symkin.kinematics import quantities as kinematics_quantities
from symkin.parallel import quantities as parallel_quantities


def test_fk_alone_derives_no_jacobian_and_no_dynamics(models):
    d = Derivation(models["ur10e"])
    d.functions(["fk"])
    assert d.computed == ["chain", "fk"]


def test_quantities_are_memoized(models):
    d = Derivation(models["ur10e"])
    first = d["jacobian"]
    assert d["jacobian"] is first
    d["jacobian_geometric"]
    assert d.computed.count("chain") == 1
    assert d.computed.count("jacobian_geometric_matrix") == 1


def test_only_fk_on_the_command_line_is_recorded_in_the_manifest(tmp_path):
    subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "ur10e.yaml"), "--only", "fk", "-o", str(tmp_path), "-q"],
                   check=True)
    manifest = json.loads((tmp_path / "ur10e" / "manifest.json").read_text())
    assert manifest["derived_quantities"] == ["chain", "fk"]
    assert [f["name"] for f in manifest["functions"]] == ["fk"]
    text = (tmp_path / "ur10e" / "ur10e.py").read_text()
    assert "def jacobian" not in text


def test_manifest_describes_every_function(generated_dir):
    manifest = json.loads((generated_dir / "ur10e" / "manifest.json").read_text())
    assert manifest["model"]["name"] == "ur10e"
    assert manifest["model"]["hash"].startswith("sha256:")
    assert manifest["generator"]["symkin"]
    fk = next(f for f in manifest["functions"] if f["name"] == "fk")
    assert fk["inputs"][0] == {"name": "q", "kind": "vector", "shape": [6],
                               "elements": ["q1", "q2", "q3", "q4", "q5", "q6"], "units": ["rad"] * 6,
                               "doc": "joint coordinates"}
    assert fk["outputs"][0]["name"] == "base_T_tcp"
    assert fk["outputs"][0]["shape"] == [4, 4]
    assert fk["op_counts"]["cse"] < fk["op_counts"]["derived"]
    assert fk["backends"] == ["c", "casadi", "jax", "js", "numpy"]
    assert manifest["backends"]["numpy"]["files"] == ["ur10e.py"]
    assert manifest["backends"]["c"]["files"] == ["ur10e.c", "ur10e.h"]
    assert manifest["backends"]["js"]["files"] == ["ur10e.js"]
    assert "ur10e_fk.casadi" in manifest["backends"]["casadi"]["files"]
    assert manifest["options"] == {"float32": False}


def test_unknown_output_on_the_command_line_is_a_usage_error(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "ur10e.yaml"), "--only", "fk,jacobain",
                                          "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2
    assert "unknown output 'jacobain'" in result.stderr
    assert "jacobian" in result.stderr
    assert not (tmp_path / "out").exists()


def test_folding_parameters_removes_them_from_the_inputs(models):
    model = models["planar_2r"]
    result = pipeline.generate(model, pipeline.resolve_request(model, "fk", "numpy", "l1"))
    (fk,) = result.manifest["functions"]
    assert [i["name"] for i in fk["inputs"]] == ["q", "l2"]
    assert "folded" in fk["op_counts"]
    with pytest.raises(ModelError, match="unknown parameter 'l9'"):
        pipeline.resolve_request(model, "fk", "numpy", "l9")


def test_the_catalog_refuses_a_quantity_defined_twice_and_keeps_definition_order():
    """The catalog is built from an explicit list of modules (nothing registers on import)."""
    first, second = types.ModuleType("first"), types.ModuleType("second")

    def define(module, name, mechanism="serial"):
        def compute(d):
            return name
        compute.__module__ = module.__name__
        setattr(module, f"{name}_{mechanism}", quantity(name, name, mechanism=mechanism)(compute))

    define(first, "b"), define(first, "a"), define(second, "b", "parallel")
    table = catalog.collect((first, second))
    assert list(table) == ["b", "a"]
    assert set(table["b"]) == {"serial", "parallel"}
    define(second, "a")
    with pytest.raises(ValueError, match="'a' defined twice"):
        catalog.collect((first, second))
    assert list(catalog.QUANTITIES)[:3] == ["chain", "fk", "frames"]  # the order of QUANTITY_MODULES


def test_internal_quantities_cannot_be_emitted(models):
    assert "chain" not in emitted_quantities()
    with pytest.raises(DerivationError, match="not an output"):
        Derivation(models["planar_2r"]).functions(["chain"])


def test_task_coordinates_need_coordinate_components(models):
    with pytest.raises(DerivationError, match="angular velocity"):
        Derivation(models["ur10e"])["task_coordinates"]


def test_available_keeps_what_the_model_can_derive_and_says_why_not(models):
    d = Derivation(models["delta"])
    kept, skipped = d.available(["ik", "frames", "no_such_quantity", "jacobian"])
    assert kept == ["ik", "jacobian"]
    assert set(skipped) == {"frames", "no_such_quantity"}
    assert "serial" in skipped["frames"]
    assert "unknown quantity" in skipped["no_such_quantity"]
    assert "frames" not in d.computed


def test_quantities_ask_for_each_other_by_their_marked_functions_not_by_name(models):
    """Issue 11: typed keys. Inside the quantity modules no derivation is indexed with a string, and a
    marked function and its name reach the same memoized value; a quantity of the other mechanism is refused."""
    for module in catalog.QUANTITY_MODULES:
        tree = ast.parse(inspect.getsource(module))
        string_keys = [f"{module.__name__}:{node.lineno}" for node in ast.walk(tree)
                       if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant)
                       and isinstance(node.slice.value, str)]
        assert not string_keys, f"quantity looked up by name (use the marked function): {string_keys}"
    arm = Derivation(models["ur10e"])
    assert arm[kinematics_quantities.chain_frames] is arm["chain"]
    assert arm[kinematics_quantities.task_jacobian] is arm["jacobian"]
    with pytest.raises(DerivationError, match="derived for parallel mechanisms"):
        arm[parallel_quantities._ik]
    with pytest.raises(DerivationError, match="neither a quantity name nor a function marked"):
        arm[len]

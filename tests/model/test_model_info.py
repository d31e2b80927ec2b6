"""The typed view of a loaded model (symkin.runtime.info.ModelInfo): built once from the manifest, read by every consumer."""

from __future__ import annotations

import json

import numpy as np

from conftest import GENERATED_DIR, MODELS_DIR
from symkin import derive, load
from symkin.mechanism import reach
from symkin.model import load_model
from tolerances import KINEMATICS


def test_the_view_says_what_the_manifest_records():
    arm = load(GENERATED_DIR / "planar_2r")
    manifest = json.loads((GENERATED_DIR / "planar_2r" / "manifest.json").read_text())
    info = arm.info
    assert info.name == "planar_2r"
    assert info.mechanism == "serial"
    assert not info.is_parallel
    assert info.coordinate_names == tuple(c["name"] for c in manifest["model"]["coordinates"])
    assert all(c.revolute for c in info.coordinates)
    assert [c.limits for c in info.coordinates] == [tuple(c["limits"]) for c in manifest["model"]["coordinates"]]
    assert info.task_space == tuple(manifest["model"]["task_space"])
    assert info.units["l1"] == "m"
    assert set(info.functions) == set(arm.functions)
    assert info.functions["fk"].parameters == tuple(i["name"] for f in manifest["functions"] if f["name"] == "fk"
                                                   for i in f["inputs"] if i["kind"] == "parameter")
    assert info.functions["fk"].vectors["q"].elements == info.coordinate_names
    assert arm.bind(l1=0.2).info == info  # binding values changes no description


def test_a_parallel_view_and_a_platform_held_at_a_constant_orientation():
    delta = load(GENERATED_DIR / "delta")
    assert delta.info.is_parallel
    assert delta.info.home == (0.0, 0.0, -0.15)
    assert len(delta.info.passive_limits) == 3
    stewart = load(GENERATED_DIR / "stewart")
    held = reach.constant_orientation(stewart, np.zeros(3))
    assert stewart.info.task_space == ("x", "y", "z", "roll", "pitch", "yaw")
    assert held.info.task_space == reach.TWIST_COMPONENTS  # a view, the loaded model is untouched
    assert held.info.coordinates == stewart.info.coordinates
    assert held.manifest is stewart.manifest


def test_the_model_hash_names_the_mechanism_not_what_is_emitted_from_it(tmp_path):
    """Issue 11: changing the ``scene:`` section (outputs, backends, folded parameters) keeps the hash;
    changing the mechanism changes it; two scenes of one model load side by side as distinct modules."""
    source = (MODELS_DIR / "planar_2r.yaml").read_text()
    scene_start = source.index("\nscene:")
    fk_only = source[:scene_start] + "\nscene:\n  outputs: [fk]\n  backends: [numpy]\n  fixed: [l1]\n"
    longer_link = source.replace("l2: {value: 0.1,", "l2: {value: 0.12,", 1)
    assert longer_link != source
    files = {}
    for name, text in {"full": source, "fk_only": fk_only, "longer": longer_link}.items():
        (tmp_path / name).mkdir()
        files[name] = tmp_path / name / "planar_2r.yaml"
        files[name].write_text(text)
    hashes = {name: load_model(path).hash for name, path in files.items()}
    assert hashes["full"] == hashes["fk_only"] == load_model(MODELS_DIR / "planar_2r.yaml").hash
    assert hashes["longer"] != hashes["full"]

    full = load(derive(files["full"], tmp_path / "out_full", backends=["numpy"]))
    folded = load(derive(files["fk_only"], tmp_path / "out_fk"))
    assert full.info.parameters != folded.info.parameters  # l1 is an input of one, folded in the other
    q = np.array([0.3, -0.7])
    np.testing.assert_allclose(folded.fk(q), full.fk(q), rtol=0, atol=KINEMATICS)
    assert set(folded.functions) == {"fk"}
    assert "mass_matrix" in full.functions

"""The typed view of a loaded model (symkin.runtime.info.ModelInfo): built once from the manifest, read by every consumer."""

from __future__ import annotations

import json

import numpy as np

from conftest import GENERATED_DIR
from symkin import load
from symkin.analysis import parallel


def test_the_view_says_what_the_manifest_records():
    arm = load(GENERATED_DIR / "planar_2r")
    manifest = json.loads((GENERATED_DIR / "planar_2r" / "manifest.json").read_text())
    info = arm.info
    assert info.name == "planar_2r" and info.mechanism == "serial" and not info.is_parallel
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
    assert delta.info.is_parallel and delta.info.home == (0.0, 0.0, -0.15)
    assert len(delta.info.passive_limits) == 3
    stewart = load(GENERATED_DIR / "stewart")
    held = parallel.constant_orientation(stewart, np.zeros(3))
    assert stewart.info.task_space == ("x", "y", "z", "roll", "pitch", "yaw")
    assert held.info.task_space == parallel.TWIST_COMPONENTS  # a view, the loaded model is untouched
    assert held.info.coordinates == stewart.info.coordinates and held.manifest is stewart.manifest

"""Issue 33 on a device haptics engineers build: the PHANToM Premium 1.5 (models/phantom_premium.yaml: a coupled
chain, its elbow driven through a parallelogram from the base, capstan drives) identified from a run.

The run is simulated with the model's own regressor (tau = Y pi) along a periodic excitation, with noise on the
efforts; `symkin identify --method consistent` must give back every base parameter within 5 of its standard
deviations (weighted least squares), and its identified.yaml must hold rigid bodies: the published model's upper
arm and lever break the triangle inequality (Cavusoglu et al. 2002, the model file's `allow_nonphysical: true`),
the consistent estimate's bodies do not, so the model reader takes the file with that permission removed.
"""

from __future__ import annotations

import json
import subprocess

import numpy as np

from conftest import MODELS_DIR, SYMKIN_CLI
from identification_runs import excitation, write_run
from symkin import pipeline
from symkin.model import load_model, model_from_text
from symkin.runtime.loader import load

#: Noise on the efforts (N m): large against rounding, small against the PHANToM's ~0.1 N m at the joints.
NOISE = 1e-4


def test_the_phantom_is_identified_from_its_motors_and_its_consistent_bodies_are_rigid(tmp_path):
    model = load_model(MODELS_DIR / "phantom_premium.yaml")
    request = pipeline.resolve_request(model, ("regressor", "base_regressor"), "numpy", None, False, "none")
    arm = load(pipeline.write(pipeline.generate(model, request), tmp_path / "generated"), "numpy")
    names = arm.info.coordinate_names
    t, q, qd, qdd = excitation(len(names), seed=2)
    q = q - 0.7                                                       # excitation() swings about 0.7 rad
    Y, pi = arm.regressor(q, qd, qdd)
    tau = np.einsum("kij,kj->ki", Y, pi) + np.random.default_rng(2).normal(0, NOISE, q.shape)
    run = write_run(tmp_path / "run.csv", names, t, q, tau, qd, qdd)
    out = tmp_path / "out"
    result = subprocess.run(SYMKIN_CLI + ["identify", str(MODELS_DIR / "phantom_premium.yaml"), str(run), "--method",
                                          "consistent", "--no-figure", "-o", str(out)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((out / "estimate.json").read_text())
    assert len(record["parameters"]) == 31
    error = {row["name"]: abs(row["value"] - row["model"]) / row["std"] for row in record["parameters"]}
    assert max(error.values()) < 5, error
    identified = (out / "identified.yaml").read_text()
    assert "allow_nonphysical: true\n" in identified
    rigid = model_from_text(identified.replace("allow_nonphysical: true\n", ""), "identified")
    assert {b.link for b in rigid.bodies} == {"turret", "upper_arm", "distal", "lever", "link_c"}

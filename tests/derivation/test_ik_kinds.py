"""The target kind of `symkin ik` follows the model's task space (issue 16).

Before, a model whose task space is neither the pose nor positions only insisted on a 6- or
16-value pose: [x, y, z, yaw] (a SCARA) and [x, y, wz] (a planar arm that orients its tool).
Now a task-space target has one value per component, wz being the rotation vector's component
(the angle about z for a planar arm), and a generated directory that lacks what task targets
need gets an error naming it.
"""

from __future__ import annotations

import json
import subprocess

import numpy as np

from conftest import SYMKIN_CLI
from sample_models import SCARA as FEASIBILITY_SCARA

PLANAR_3R = """name: planar_3r
serial:
  dh:
    convention: classic
    rows:
      - [q1, R, 0, 0, 0.3, 0, [-3, 3]]
      - [q2, R, 0, 0, 0.25, 0, [-3, 3]]
      - [q3, R, 0, 0, 0.1, 0, [-3, 3]]
task_space: [x, y, wz]
"""

#: The SCARA of the feasibility tests, with the task space of a pick-and-place robot.
SCARA = FEASIBILITY_SCARA.replace("task_space: [x, y, z, wz]", "task_space: [x, y, z, yaw]")


def _ik(model, *target, extra=()):
    return subprocess.run(SYMKIN_CLI + ["ik", str(model), "-t", *map(str, target), "--json", *extra],
                          capture_output=True, text=True)


def _planar_3r_tcp(q):
    angles = np.cumsum(q)
    lengths = np.array([0.3, 0.25, 0.1])
    return [float(lengths @ np.cos(angles)), float(lengths @ np.sin(angles)), float(angles[-1])]


def test_a_planar_arm_with_an_orientation_takes_x_y_and_the_angle(tmp_path):
    model = tmp_path / "planar_3r.yaml"
    model.write_text(PLANAR_3R)
    target = _planar_3r_tcp(np.array([0.4, 0.7, -0.5]))
    run = _ik(model, *target)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["kind"] == "task"
    solutions = [s["q"] for t in report["targets"] for s in t["solutions"]]
    assert solutions
    assert all(np.allclose(_planar_3r_tcp(np.array(q)), target, atol=1e-10) for q in solutions)


def test_a_scara_takes_x_y_z_and_yaw(tmp_path):
    model = tmp_path / "scara.yaml"
    model.write_text(SCARA)
    run = _ik(model, 0.35, 0.2, 0.3, 0.4)
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["kind"] == "task"


def test_a_generated_directory_without_task_coordinates_names_what_to_derive(tmp_path):
    model = tmp_path / "scara.yaml"
    model.write_text(SCARA)
    out = tmp_path / "out"
    assert subprocess.run(SYMKIN_CLI + ["derive", str(model), "--only", "fk,jacobian", "-o", str(out), "-q"]
                          ).returncode == 0
    run = _ik(out / "scara", 0.35, 0.2, 0.3, 0.4)
    assert run.returncode == 2
    assert "task_coordinates" in run.stderr
    assert "6 values or 16" not in run.stderr

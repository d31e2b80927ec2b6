"""Rough edges a first-time user hit (issue 16), each with the test that failed before its fix."""

from __future__ import annotations

import subprocess
import tomllib

import numpy as np

from conftest import GENERATED_DIR, MODELS_DIR, ROOT, SYMKIN_CLI
from symkin import load
from symkin.simulation import Plant, scenarios


def test_the_repository_has_the_licence_its_metadata_names():
    metadata = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert metadata["license"] == "MIT"
    assert "LICENSE" in metadata.get("license-files", [])
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert not list(ROOT.glob("*.png"))  # no stray figure at the root (ur10e-stability.png was committed)


def test_bench_stability_derives_what_it_needs_and_writes_its_figure_under_out(tmp_path):
    run = subprocess.run(SYMKIN_CLI + ["bench", "stability", str(MODELS_DIR / "planar_2r.yaml"), "--only",
                                       "mass_matrix", "--samples", "4", "--scale-samples", "1", "--float32-samples",
                                       "2"], cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr  # was: "inverse kinematics needs the generated 'fk'"
    assert (tmp_path / "out" / "figures" / "planar_2r-stability.png").exists()
    assert not list(tmp_path.glob("*.png"))


def test_figures_and_outputs_get_the_permissions_of_the_umask(tmp_path):
    """workspace wrote its PNG 0600 (a private temporary file renamed into place), simulate 0644."""
    script = (f"umask 022 && {' '.join(SYMKIN_CLI)} workspace {GENERATED_DIR / 'planar_2r'} -n 300 -o ws.png "
              f"&& {' '.join(SYMKIN_CLI)} export {MODELS_DIR / 'planar_2r.yaml'} -o arm.urdf "
              f"&& {' '.join(SYMKIN_CLI)} derive {MODELS_DIR / 'planar_2r.yaml'} --only fk -o out -q")
    run = subprocess.run(["bash", "-c", script], cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    for path in (tmp_path / "ws.png", tmp_path / "arm.urdf", tmp_path / "out" / "planar_2r" / "manifest.json"):
        assert path.stat().st_mode & 0o777 == 0o644, path
    assert (tmp_path / "out" / "planar_2r").stat().st_mode & 0o777 == 0o755


def test_the_sine_scenario_labels_rotational_task_forces_in_newton_metres_and_cites_the_seed_only_for_its_arm():
    ur = Plant(load(GENERATED_DIR / "ur10e"))
    center = np.array([0.3, -1.2, 1.4, -1.6, -1.5, 0.2])
    result = scenarios.sine([("ur10e", ur)], center, 1, 0.1, 1.0, scenarios.Timing(0.02, 1000, "rk4"))
    columns = result.series[0].columns
    assert "F_x [N]" in columns
    assert "F_wz [N m]" in columns
    assert "F_wz [N]" not in columns
    line = next(text for text in result.summary if "peak TCP forces" in text)
    assert "|F_wz| <= " in line
    assert line.rstrip().endswith("N m")
    assert "|F_x| <= " in line
    assert all("seed" not in figure.title.lower() for figure in result.figures[:2])
    arm = Plant(load(GENERATED_DIR / "planar_2r"))
    seed = scenarios.sine([("arm", arm)], np.radians([45, 45]), 1, 0.1, 1.0, scenarios.Timing(0.02, 1000, "rk4"))
    assert "(seed Fig. 8.21)" in seed.figures[0].title
    assert "(seed Fig. 8.22)" in seed.figures[1].title


def test_simulate_starts_from_a_well_conditioned_pose_and_says_which(tmp_path):
    """Symmetric limits put a SCARA's default start (the middle of the limits) on its stretched-arm
    singularity: the sine scenario gave 2001 NaN TCP-force samples.  Now the start is the best-
    conditioned pose of a Sobol set within the limits, and the output says so."""
    from sample_models import SCARA

    model = tmp_path / "scara.yaml"
    model.write_text(SCARA.replace("{link: link4, mass: 0.5}",
                                   "{link: link4, mass: 0.5, inertia: {xx: 1e-4, yy: 1e-4, zz: 2e-4}}"))
    run = subprocess.run(SYMKIN_CLI + ["simulate", str(model), "--scenario", "sine", "--duration", "0.2", "-o",
                                       str(tmp_path / "out"), "--no-figure"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "start: q0 = [" in run.stdout
    assert "best-conditioned of 256 poses" in run.stdout
    assert "singular configuration" not in run.stdout  # no NaN TCP forces
    # each joint with its own unit: the prismatic q3 in m and N, no "N m|N" mixed into one line
    assert "|tau_q3| <= " in run.stdout
    assert "N m|N" not in run.stdout
    assert "rad|m, k =" not in run.stdout
    assert "q3: [0, 0.2] m, k = " in run.stdout
    assert "tau_q1 > tau_q2 at every sample" not in run.stdout  # the seed's remark is for its 2R arm only
    seed = subprocess.run(SYMKIN_CLI + ["simulate", str(GENERATED_DIR / "planar_2r"), "--scenario", "sine",
                                        "--duration", "0.05", "-o", str(tmp_path / "arm"), "--no-figure"],
                          capture_output=True, text=True)
    assert seed.returncode == 0, seed.stderr
    assert "the middle of the joint limits (1/kappa = " in seed.stdout, seed.stderr

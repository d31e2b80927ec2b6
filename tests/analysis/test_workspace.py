"""Workspace (seed sec. 4.1, 5.2): limits from the manifest, sampling, reachability, boundary, singularities."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin.mechanism import feasibility
from symkin.analysis import global_indices, grids, inverse, workspace
from symkin import mechanism
from symkin.mechanism import reach
from symkin.analysis.inverse import closed_form_inverse
from symkin.mechanism.limits import within_limits
from symkin.errors import NotApplicable
from symkin.runtime import LoadedModel

from conftest import EXAMPLE_MODELS, GENERATED_DIR
from tolerances import CLOSED_FORM, KINEMATICS

ARM = symkin.load(GENERATED_DIR / "planar_2r")


def _seed_fk(q, l1=0.1, l2=0.1):
    return np.stack([l1 * np.cos(q[..., 0]) + l2 * np.cos(q[..., 0] + q[..., 1]),
                     l1 * np.sin(q[..., 0]) + l2 * np.sin(q[..., 0] + q[..., 1])], axis=-1)


# --- what the analyses read from the manifest ---------------------------------------------------


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_manifest_limits_are_the_model_files_limits(models, name):
    """Declared limits at the default parameters; an undeclared revolute range is one turn,
    an undeclared prismatic range is an error that names the coordinate."""
    model = models[name]
    loaded = symkin.load(GENERATED_DIR / name)
    unbounded = [c.name for c in model.coordinates if c.limits is None and c.type.value == "P"]
    if unbounded:
        with pytest.raises(ValueError, match=f"prismatic joint '{unbounded[0]}' declares no limits"):
            mechanism.joint_limits(loaded)
        return
    expected = [[float(b.xreplace(model.parameter_values)) for b in c.limits] if c.limits is not None
                else [-np.pi, np.pi] for c in model.coordinates]
    assert np.array_equal(mechanism.joint_limits(loaded), np.array(expected))


def test_limit_overrides_and_defaults():
    assert np.allclose(mechanism.joint_limits(ARM), [[0, np.pi / 2]] * 2)
    override = mechanism.joint_limits(ARM, {"theta2": (-1.0, 1.0)})
    assert np.allclose(override, [[0, np.pi / 2], [-1, 1]])
    with pytest.raises(ValueError, match="no coordinates named"):
        mechanism.joint_limits(ARM, {"theta3": (0, 1)})
    with pytest.raises(ValueError, match="not finite intervals"):
        mechanism.joint_limits(ARM, {"theta1": (1, 0)})

    stub = LoadedModel(Path("."), {"model": {"name": "stub", "task_space": ["x", "y"],
                                             "coordinates": [{"name": "a", "type": "R"}, {"name": "s", "type": "P"}]},
                                   "parameters": [], "functions": []}, "numpy", {})
    with pytest.raises(ValueError, match="prismatic joint 's' declares no limits"):
        mechanism.joint_limits(stub)
    assert np.allclose(mechanism.joint_limits(stub, {"s": (0, 0.5)}), [[-np.pi, np.pi], [0, 0.5]])


# --- point clouds ---------------------------------------------------------------------------------


@pytest.mark.parametrize("method", workspace.SAMPLING_METHODS)
def test_point_cloud_is_the_forward_kinematics_of_configurations_within_limits(method):
    cloud = workspace.sample_workspace(ARM, 1000, method=method, seed=1)
    assert cloud.axes == ("x", "y")
    assert np.all((cloud.q >= 0) & (cloud.q <= np.pi / 2))
    assert np.allclose(cloud.points, _seed_fk(cloud.q), rtol=0, atol=CLOSED_FORM)  # the 2R FK, reach < 1 m
    if method == "grid":
        assert cloud.grid_shape == (32, 32)
        assert {0.0, np.pi / 2} <= set(np.unique(cloud.q[:, 1]))  # the limits themselves are sampled


def test_ur10e_cloud_is_three_dimensional_within_reach():
    ur = symkin.load(GENERATED_DIR / "ur10e")
    cloud = workspace.sample_workspace(ur, 4096, seed=0)
    assert cloud.axes == ("x", "y", "z")
    assert cloud.grid_shape is None  # 6 joints: Sobol by default
    longest = 0.6127 + 0.57155 + 0.17415 + 0.11985 + 0.11655 + 0.1807
    assert np.all(np.linalg.norm(cloud.points, axis=1) <= longest)


def test_bounding_box_contains_the_workspace():
    for arm in (ARM, ARM.bind(l1=0.3, l2=0.05)):
        points = workspace.sample_workspace(arm, 200_000, method="random", seed=2).points
        extent = points.max(axis=0) - points.min(axis=0)
        for samples, slack in ((64, 2.0), (reach.BOX_SAMPLES, 1.05)):  # coarse joint grids pad more
            lower, upper = reach.bounding_box(arm, samples=samples)
            assert np.all(points >= lower)
            assert np.all(points <= upper)
            assert np.all(upper - lower < slack * extent)


# --- reachability (inverse kinematics) ----------------------------------------------------------


def test_closed_form_inverse_adapts_symkin_ik_to_positions_and_refuses_pose_solvers():
    """The planar arm's symkin.ik solver, bound parameters included; boundary points (the
    stretched and the folded arm, |cos theta2| = 1) stay reachable; the UR10e's solver
    takes poses and is refused."""
    arm = ARM.bind(l1=0.3, l2=0.12)
    ik = closed_form_inverse(arm)
    assert (ik.dimension, ik.branches) == (2, 2)
    assert ik.solver.name == "planar 2R"
    rim = 0.42 * np.array([np.cos(np.linspace(0, 2 * np.pi, 37)), np.sin(np.linspace(0, 2 * np.pi, 37))]).T
    hole = rim * (0.18 / 0.42)
    for points, theta2 in ((rim, 0.0), (hole, np.pi)):
        q, valid = ik.solve(points)
        assert valid.all()
        assert np.allclose(np.abs(np.angle(np.exp(1j * q[..., 1]))), theta2, atol=1e-7)
        # FK of the IK's angles: backward stable, KINEMATICS of the reach l1 + l2 = 0.42 m
        assert np.allclose(mechanism.tcp_positions(arm, q), points[:, None], rtol=0, atol=KINEMATICS * 0.42)
    _, valid = ik.solve(rim * (1 + 1e-12))
    assert not valid.any()
    with pytest.raises(NotApplicable, match="takes pose targets"):
        closed_form_inverse(symkin.load(GENERATED_DIR / "ur10e"))
    assert isinstance(inverse.inverse_kinematics_for(ARM), inverse.ClosedFormInverse)


def test_only_a_named_not_applicable_means_the_next_inverse_is_tried(monkeypatch):
    """inverse_kinematics_for goes on past NotApplicable; a real error inside a factory surfaces."""
    def broken(model):
        raise ValueError("a bug inside the analysis")

    def not_mine(model):
        raise NotApplicable("not this kind of model")

    monkeypatch.setattr(inverse, "INVERSE_FACTORIES", [not_mine, closed_form_inverse])
    assert isinstance(inverse.inverse_kinematics_for(ARM), inverse.ClosedFormInverse)
    monkeypatch.setattr(inverse, "INVERSE_FACTORIES", [broken, closed_form_inverse])
    with pytest.raises(ValueError, match="a bug inside the analysis"):
        inverse.inverse_kinematics_for(ARM)
    monkeypatch.setattr(inverse, "INVERSE_FACTORIES", [not_mine])
    assert inverse.inverse_kinematics_for(ARM) is None


def test_inverse_kinematics_round_trips_on_both_branches():
    arm = ARM.bind(l1=0.25, l2=0.1)
    ik = closed_form_inverse(arm)
    q = np.random.default_rng(3).uniform(-np.pi, np.pi, (500, 2))
    points = mechanism.tcp_positions(arm, q)
    solutions, valid = ik.solve(points)
    assert valid.all()
    for branch in range(ik.branches):
        assert np.allclose(mechanism.tcp_positions(arm, solutions[:, branch]), points, rtol=0, atol=KINEMATICS * 0.35)
    # One of the two branches is the configuration we started from (angles modulo 2 pi).
    wrapped = np.angle(np.exp(1j * (solutions - q[:, None, :])))
    assert np.all(np.min(np.abs(wrapped).max(axis=2), axis=1) < 1e-9)
    # Beyond the reach (r > l1 + l2) or inside the hole (r < l1 - l2): no solution.
    _, valid = ik.solve(np.array([[0.36, 0.0], [0.0, 0.14], [0.1, 0.0]]))
    assert not valid.any()


def test_reachability_respects_joint_limits():
    ik = closed_form_inverse(ARM)
    limits, revolute = mechanism.joint_limits(ARM), mechanism.revolute_mask(ARM)
    inside = workspace.sample_workspace(ARM, 2000, method="random", seed=4)
    assert feasibility.reachable(ik, inside.points, limits, revolute).all()
    q_out = np.random.default_rng(5).uniform([-np.pi, -np.pi], [-0.1, -0.1], (500, 2))  # both joints below 0
    assert not feasibility.reachable(ik, _seed_fk(q_out), limits, revolute).any()
    q, ok = feasibility.feasible_configurations(ik, inside.points, limits, revolute)
    assert ok.all()
    assert np.allclose(q, inside.q, atol=1e-7)


def test_within_limits_wraps_angles_only():
    limits = np.array([[0.0, np.pi / 2], [0.0, 1.0]])
    q, inside = within_limits(np.array([[2 * np.pi + 0.5, 0.5], [-1e-12, 0.5], [0.5, 1.5], [0.5, 2 * np.pi + 0.5]]),
                              limits, np.array([True, False]))
    assert np.allclose(q[0], [0.5, 0.5])
    assert inside[0]
    assert inside[1]  # rounding just below a limit is inside
    assert not inside[2]
    assert not inside[3]  # a prismatic coordinate is not periodic


# --- occupancy, area, boundary and singularities ------------------------------------------------


def test_occupancy_brackets_the_exact_area():
    for l in (0.1, 0.2):
        cloud = workspace.sample_workspace(ARM.bind(l1=l, l2=l), 40_000)
        area = workspace.occupancy_from_cloud(cloud).measure()
        assert abs(area.value - np.pi / 2 * l * l) <= area.error


def test_boundary_singularities_lie_on_the_workspace_boundary():
    """Seed sec. 4.2: the stretched arm (theta2 = 0, det J = 0) is a workspace-boundary singularity."""
    cloud = workspace.sample_workspace(ARM, 40_000)
    singular = global_indices.singular(ARM, cloud.q)
    assert np.array_equal(singular, np.isclose(cloud.q[:, 1], 0.0))  # exactly the theta2 = 0 samples
    occupancy = workspace.occupancy_from_cloud(cloud)
    boundary = occupancy.boundary()
    assert occupancy.lookup(cloud.points[singular], boundary).all()
    assert np.allclose(np.linalg.norm(cloud.points[singular], axis=1), 0.2)  # the outer arc r = l1 + l2
    # Well-conditioned configurations in the middle of the joint box are interior.
    middle = np.all(np.abs(cloud.q - np.pi / 4) < 0.2, axis=1)
    assert not occupancy.lookup(cloud.points[middle], boundary).any()


def test_reachability_grid_finds_the_same_workspace_and_boundary():
    ik = closed_form_inverse(ARM)
    grid = grids.reachability_grid(ARM, ik, reach.bounding_box(ARM), 0.002)
    area = grid.occupied.sum() * grid.cell_volume
    assert area == pytest.approx(np.pi / 2 * 0.01, rel=0.02)
    # The stretched arm away from the two cusps (where the workspace is thinner than a cell).
    stretched = _seed_fk(np.column_stack([np.linspace(0.1, np.pi / 2 - 0.1, 50), np.zeros(50)]))
    boundary = grid.boundary()
    neighbourhood = np.zeros_like(boundary)  # the arc may pass through an unreachable cell next to the boundary
    for shift in np.ndindex(3, 3):
        neighbourhood |= np.roll(boundary, (shift[0] - 1, shift[1] - 1), axis=(0, 1))
    assert grid.lookup(stretched, neighbourhood).all()


def test_limit_curves_trace_the_fig_8_19_outline():
    curves = workspace.limit_curves(ARM, count=50)
    assert len(curves) == 4
    radius = [np.linalg.norm(c, axis=1) for c in curves]
    assert np.allclose(radius[2], 0.2)  # theta2 = 0: the outer arc
    assert np.allclose(radius[3], np.hypot(0.1, 0.1))  # theta2 = 90 deg: the inner arc


def test_analyses_do_not_import_sympy():
    """Analyses run on generated code only: data flows one way, and a design loop pays for numpy and scipy."""
    import subprocess
    import sys

    code = ("import sys; import symkin; from symkin import analysis; "
            f"arm = symkin.load({str(GENERATED_DIR / 'planar_2r')!r}); "
            "analysis.gci(arm, method='qmc', samples=1024, seed=0); "
            "analysis.sample_workspace(arm, 100); "
            "import symkin.analysis.plots, symkin.analysis.convergence; "
            "print('sympy' in sys.modules, 'jinja2' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_the_volumes_say_which_sets_they_measure_where_the_joints_cover_the_workspace_twice(capsys):
    """Issue 64 ("one workspace, one volume"): the joint domain's figure integrates |det J| over the joint limits, so
    a point reached by two configurations counts twice.  The 2R arm with its elbow free over a full turn reaches
    its workspace elbow up and elbow down: that figure (2 pi l1 l2, exactly) exceeds every occupied
    cell, and the report says the figures measure different sets; at its declared limits (one branch) it does not.
    The PHANToM's joint limits reached parts of its workspace twice as well until its model declared the
    parallelogram's stops: within them its two volumes agree (docs/analysis.md quotes them)."""
    from symkin.cli import main

    said = {}
    for name, extra in (("planar_2r", []), ("planar_2r", ["--limit", "theta2=-180deg:180deg"]),
                        ("phantom_premium", [])):
        assert main(["workspace", str(GENERATED_DIR / name), "--no-figure", *extra]) == 0
        said[name, bool(extra)] = capsys.readouterr().out
    assert "measure different sets" not in said["planar_2r", False]
    covered = said["planar_2r", True]
    assert "area: 0.0628318" in covered        # l1 l2 (pi/2) int of |sin theta2| over a turn = 2 pi l1 l2
    assert "the areas measure different sets" in covered
    assert "is the Cartesian box's and the occupancy's" in covered
    phantom = said["phantom_premium", False]
    assert "measure different sets" not in phantom
    # the joint domain's volume and the occupancy's bracket, within the stops, as docs/analysis.md quotes them
    (joint, error), (occupied, half_width) = (tuple(map(float, found)) for found in re.findall(
        r"volume: ([0-9.e-]+) \+- ([0-9.e-]+) m\^3", phantom))
    assert round(joint, 4) == 0.0958
    assert abs(joint - occupied) <= error + half_width
    assert (round(occupied, 3), round(half_width, 3)) == (0.088, 0.048)


def test_the_phantoms_largest_box_and_cylinder_are_the_ones_the_docs_quote(capsys):
    """Issue 64: symkin workspace prints the largest box and upright cylinder inside the interior cells; on the
    PHANToM with a million samples, the figures of docs/analysis.md (mm)."""
    from symkin.cli import main

    assert main(["workspace", str(GENERATED_DIR / "phantom_premium"), "--no-figure", "-n", "1000000"]) == 0
    said = capsys.readouterr().out
    assert "largest box inside (interior cells, axis-aligned): 113 x 357 x 357 mm" in said
    assert "largest upright cylinder inside: diameter 161 mm x height 357 mm" in said

"""Design sweeps on Dask (issue 15): the same rows to the bit however they are scheduled, nothing lost.

Oracles: the GCI and workspace measure of a design computed directly with
:func:`symkin.analysis.global_indices.gci` on the bound model (the sweep must give the same
numbers); the planar 2R's workspace area pi ((l1 + l2)^2 - (l1 - l2)^2) / 4 within its
quarter-turn limits... (exact: the annulus sector swept by the two quarter turns is checked
through the integrator's own error bar); the GCI-optimal ratio l2 / l1 = 1 / sqrt(2) of the
2R arm (Salisbury and Craig 1982; the seed's Table 8.5 neighbourhood); a serial run as the
reference of the LocalCluster runs, the interrupted and resumed run and the run that loses a
worker.
"""

from __future__ import annotations

import math
import os
import signal

import numpy as np
import pyarrow.parquet as pq
import pytest
from conftest import GENERATED_DIR, MODELS_DIR

from symkin import design
from symkin.analysis.global_indices import gci
from symkin.cli import main
from symkin.design.sweeps import EMPTY, OK, SweepAxis, SweepDefinition, evaluate_missing, parse_axis
from symkin.runtime.payload import ModelPayload
from symkin.design.sweep_store import SweepStore, read_sweep

#: one worker runs the Dask tests: each starts a LocalCluster of 2 processes on the 2 cores
pytestmark = pytest.mark.xdist_group("dask")

GRID = SweepDefinition((SweepAxis("l1", 0.05, 0.30, 6), SweepAxis("l2", 0.05, 0.30, 6)), chunk=5, samples=1024)


@pytest.fixture(scope="module")
def payload():
    return ModelPayload.from_directory(GENERATED_DIR / "planar_2r")


@pytest.fixture(scope="module")
def reference(payload, tmp_path_factory):
    """The grid evaluated serially, in this process."""
    store = SweepStore(tmp_path_factory.mktemp("serial") / "grid.parquet", GRID, payload)
    evaluate_missing(payload, GRID, store, scheduler="serial")
    return store.finish()


def test_designs_are_fixed_by_the_definition():
    assert GRID.size == 36
    assert GRID.chunks == 8
    designs = GRID.designs()
    np.testing.assert_array_equal(designs[:7, 0], [0.05] * 6 + [0.1])             # row-major, l2 fastest
    np.testing.assert_array_equal(np.vstack([GRID.designs(k) for k in range(GRID.chunks)]), designs)
    sobol = SweepDefinition((SweepAxis("l1", 0.1, 0.2), SweepAxis("l2", 0.0, 1.0)), sobol=100, chunk=7)
    whole = sobol.designs()
    assert whole.shape == (100, 2)
    assert len(np.unique(whole, axis=0)) == 100
    np.testing.assert_array_equal(np.vstack([sobol.designs(k) for k in range(sobol.chunks)]), whole)
    assert whole[:, 0].min() >= 0.1
    assert whole[:, 0].max() <= 0.2
    assert SweepDefinition.from_json(sobol.to_json()) == sobol
    assert parse_axis("l1=0.05:0.3:40", True) == SweepAxis("l1", 0.05, 0.3, 40)
    for text, grid in (("l1=0.05:0.3", True), ("l1=a:b:3", True), ("l1=0.1:0.2:3", False), ("=1:2:3", True)):
        with pytest.raises(ValueError, match="--vary"):
            parse_axis(text, grid)
    with pytest.raises(ValueError, match="unknown metrics"):
        SweepDefinition(GRID.axes, ("gci", "speed"))
    with pytest.raises(ValueError, match="varied twice"):
        SweepDefinition((GRID.axes[0], GRID.axes[0]))


def test_rows_are_the_gci_of_each_design(reference, payload):
    rows = reference.to_pydict()
    assert rows["design"] == list(range(36))
    assert set(rows["status"]) == {OK}
    model = payload.load()
    for i in (0, 17, 35):
        direct = gci(model.bind(l1=rows["l1"][i], l2=rows["l2"][i]), samples=GRID.samples, seed=GRID.seed)
        assert rows["gci"][i] == direct.value.value
        assert rows["gci_error"][i] == direct.value.error
        assert rows["volume"][i] == direct.measure.value
        assert rows["volume_error"][i] == direct.measure.error
        assert 1.0 <= rows["kappa_min"][i] <= 1.0 / rows["gci"][i] <= rows["kappa_max"][i]
    # the 2R arm's GCI is best near l2 / l1 = 1 / sqrt(2), for every l1 of the grid
    gcis = np.array(rows["gci"]).reshape(6, 6)
    values = GRID.axes[1].values()
    for k, l1 in enumerate(GRID.axes[0].values()[2:], start=2):
        best = values[np.argmax(gcis[k])]
        assert abs(best - l1 / math.sqrt(2)) <= values[1] - values[0], (l1, best)


def test_a_local_cluster_gives_the_same_rows_to_the_bit(reference, payload, tmp_path):
    store = SweepStore(tmp_path / "local.parquet", GRID, payload)
    evaluate_missing(payload, GRID, store, scheduler="local", workers=2)
    assert store.finish().equals(reference)
    assert pq.read_table(tmp_path / "local.parquet").equals(reference)


def test_an_interrupted_sweep_resumes_without_recomputing_or_duplicating(reference, payload, tmp_path):
    out = tmp_path / "split.parquet"
    done = []

    def interrupt(chunk: int) -> None:
        done.append(chunk)
        if len(done) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        evaluate_missing(payload, GRID, SweepStore(out, GRID, payload), scheduler="serial", chunk_done=interrupt)
    store = SweepStore(out, GRID, payload, resume=True)
    assert store.completed() == {0, 1, 2}
    resumed = []
    evaluate_missing(payload, GRID, store, scheduler="serial", chunk_done=resumed.append)
    assert resumed == [3, 4, 5, 6, 7]
    assert store.table().equals(reference)
    # a different definition does not resume these parts
    other = SweepDefinition(GRID.axes, chunk=5, samples=2048)
    with pytest.raises(ValueError, match="another definition"):
        SweepStore(out, other, payload, resume=True)


def test_a_worker_killed_mid_sweep_loses_no_design(reference, payload, tmp_path):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        pids = client.run(os.getpid)
        killed = []

        def kill_one(chunk: int) -> None:
            if not killed:
                victim = sorted(pids.values())[0]
                os.kill(victim, signal.SIGKILL)
                killed.append(victim)

        store = SweepStore(tmp_path / "killed.parquet", GRID, payload)
        evaluate_missing(payload, GRID, store, client=client, chunk_done=kill_one)
    table = store.table()
    assert killed
    assert table.column("design").to_pylist() == list(range(GRID.size))
    assert table.equals(reference)


@pytest.mark.parametrize("length", ["auto", 0.5])
def test_a_task_space_of_lengths_and_angles_is_homogenized(length, tmp_path):
    """The UR10e's task space mixes translations and rotations: every design's GCI, workspace measure and extreme
    kappas are those of its Jacobian homogenized by the definition's characteristic length - each design's own with
    "auto", as symkin gci takes it, or the one given - the same numbers as gci of the bound model (before, every
    design of such a model failed for want of a length)."""
    ur10e = ModelPayload.from_directory(GENERATED_DIR / "ur10e")
    definition = SweepDefinition((SweepAxis("a2", 0.5, 0.7, 2),), samples=256, length=length)
    store = SweepStore(tmp_path / "ur10e.parquet", definition, ur10e)
    evaluate_missing(ur10e, definition, store, scheduler="serial")
    rows = store.finish().to_pydict()
    assert rows["status"] == [OK, OK]
    for a2, found, error, volume in zip(rows["a2"], rows["gci"], rows["gci_error"], rows["volume"]):
        direct = gci(ur10e.load().bind(a2=a2), samples=definition.samples, seed=definition.seed, length=length)
        assert (found, error, volume) == (direct.value.value, direct.value.error, direct.measure.value)
    assert rows["gci"][1] > rows["gci"][0] > 0.0


@pytest.mark.parametrize("name, axis", [("stewart", SweepAxis("r_b", 0.1, 0.2, 2)),
                                        ("agile_eye", SweepAxis("r_p", 0.07, 0.09, 2))])
def test_a_platform_is_swept_over_the_domain_symkin_gci_rates_it_on(name, axis, tmp_path):
    """A Stewart-Gough platform (its Cartesian workspace at its home orientation, 1/kappa homogenized by each
    design's own length) and a spherical platform (its orientations, the invariant measure of SO(3)): every design's
    GCI, error and measure are those gci and orientation_gci give the bound model (before, every Stewart design failed
    and the Agile Eye's sweep crashed: both were integrated over the joint limits, which they are not rated on)."""
    from symkin.analysis import inverse, orientations
    from symkin.mechanism import reach

    platform = ModelPayload.from_directory(GENERATED_DIR / name)
    definition = SweepDefinition((axis,), samples=256)
    store = SweepStore(tmp_path / f"{name}.parquet", definition, platform)
    evaluate_missing(platform, definition, store, scheduler="serial")
    rows = store.finish().to_pydict()
    assert rows["status"] == [OK, OK]
    for value, found, error, volume, lowest, highest in zip(rows[axis.name], rows["gci"], rows["gci_error"],
                                                            rows["volume"], rows["kappa_min"], rows["kappa_max"]):
        bound = platform.load().bind(**{axis.name: value})
        if name == "agile_eye":
            direct = orientations.orientation_gci(bound, samples=definition.samples, seed=definition.seed)
        else:
            held = reach.held_at(bound, None)
            direct = gci(held, domain="cartesian", inverse=inverse.inverse_kinematics_for(held), length="auto",
                         samples=definition.samples, seed=definition.seed)
        assert (found, error, volume) == (direct.value.value, direct.value.error, direct.measure.value)
        assert 1.0 <= lowest <= 1.0 / found <= highest


def test_cli_says_why_designs_failed(tmp_path, capsys):
    """The Stewart platform's torque_peak needs J(q), which it has no closed form for: each design is a failed row,
    and the summary prints the first one's reason (not only a count)."""
    assert main(["sweep", str(GENERATED_DIR / "stewart"), "--vary", "r_b=0.1:0.2:2", "--metric", "gci,torque_peak",
                 "-n", "64", "--scheduler", "serial", "--no-figure", "-o", str(tmp_path / "s.parquet")]) == 0
    out = capsys.readouterr().out
    assert "designs failed      2" in out
    assert "design 0 failed: ValueError: stewart: the workspace and GCI analyses" in out
    assert "(and 1 more: the status column)" in out


def test_torque_peak_is_the_longest_lever_arm(payload, tmp_path):
    """Planar 2R: tau = J^T F, column 1 of J has the length of the TCP radius |p| (largest, l1 + l2, at
    theta2 = 0), column 2 has l2.  The Sobol net puts a point within (pi/2) / 2^6 of theta2 = 0 among
    2^12, where |p| falls short of l1 + l2 by at most l1 l2 delta^2 / (2 (l1 + l2))."""
    definition = SweepDefinition((SweepAxis("l1", 0.1, 0.2, 2), SweepAxis("l2", 0.05, 0.05, 1)),
                                 ("gci", "torque_peak"), samples=4096)
    table = design.sweep(payload, definition, scheduler="serial")
    rows = table.to_pydict()
    delta = (math.pi / 2) / 2**6
    for l1, l2, peak in zip(rows["l1"], rows["l2"], rows["torque_peak"]):
        assert l1 + l2 - l1 * l2 * delta**2 / (2 * (l1 + l2)) <= peak <= l1 + l2
    assert "kappa_min" not in rows
    delta_payload = ModelPayload.from_directory(GENERATED_DIR / "delta")
    one = SweepDefinition((SweepAxis("a", 0.1, 0.1, 1),), ("torque_peak",), samples=1024)
    peak = design.sweep(delta_payload, one, scheduler="serial").column("torque_peak")[0].as_py()
    assert 0.0 < peak < 1.0                                      # N m per N, finite (0.14 at 2^10 points)


def test_a_design_without_workspace_is_a_row_not_a_crash(payload, tmp_path):
    definition = SweepDefinition((SweepAxis("l1", 0.0, 0.1, 2), SweepAxis("l2", 0.0, 0.1, 2)), samples=256)
    table = design.sweep(payload, definition, scheduler="serial")
    rows = table.to_pydict()
    # det J = l1 l2 sin(theta2): with a zero length the workspace is an arc (or a point), of area 0
    assert rows["status"] == [EMPTY, EMPTY, EMPTY, OK]
    assert math.isnan(rows["gci"][0])
    assert rows["gci"][3] > 0.0


def test_cli_writes_the_table_with_its_metadata_and_figures(tmp_path, capsys):
    out = tmp_path / "sweep.parquet"
    assert main(["sweep", str(MODELS_DIR / "delta.yaml"), "--vary", "a=0.08:0.12:3", "--vary", "b=0.13:0.17:2",
                 "-n", "512", "--chunk", "4", "--scheduler", "serial", "-o", str(out), "--metric",
                 "gci,volume,kappa_min,kappa_max,torque_peak", "--figures", str(tmp_path / "fig")]) == 0
    printed = capsys.readouterr().out
    assert "sweep of delta: 6 designs in 2 chunks of 4, in this process" in printed
    assert "best gci" in printed
    table, definition, metadata = read_sweep(out)
    assert table.num_rows == 6
    assert set(table.column("status").to_pylist()) == {OK}
    assert metadata["symkin.model"] == "delta"
    assert metadata["symkin.model_hash"].startswith("sha256:")
    assert definition.names == ("a", "b")
    assert definition.samples == 512
    assert (tmp_path / "fig" / "delta-sweep-maps.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "fig" / "delta-sweep-pareto.png").read_bytes()[:4] == b"\x89PNG"
    assert not (tmp_path / "sweep.parquet.parts").exists()


def test_cli_marks_the_optimum_of_symkin_optimize(tmp_path, capsys):
    """The optimum of the planar arm (GCI maximal at l2 = l1 / sqrt(2)) evaluated like the designs."""
    assert main(["optimize", str(GENERATED_DIR / "planar_2r"), "--free", "l1,l2", "--bounds",
                 "l1=0.05:0.3,l2=0.05:0.3", "-o", str(tmp_path / "opt")]) == 0
    capsys.readouterr()
    assert main(["sweep", str(GENERATED_DIR / "planar_2r"), "--vary", "l1=0.05:0.3:4", "--vary", "l2=0.05:0.3:4",
                 "-n", "1024", "--scheduler", "serial", "--optimum", str(tmp_path / "opt" / "result.json"),
                 "-o", str(tmp_path / "s.parquet"), "--figures", str(tmp_path / "fig")]) == 0
    printed = capsys.readouterr().out
    line = next(row for row in printed.splitlines() if row.strip().startswith("optimum gci"))
    table, _, _ = read_sweep(tmp_path / "s.parquet")
    # the optimum is at least as good as every grid design, within the integrator's error bars
    margin = 3 * max(table.column("gci_error").to_pylist())
    assert float(line.split()[2]) >= max(table.column("gci").to_pylist()) - margin
    assert (tmp_path / "fig" / "planar_2r-sweep-pareto.png").exists()


@pytest.mark.parametrize("arguments, message", [
    (["--vary", "l1=0.1:0.2:3", "--optimum", "missing.json"], "--optimum missing.json: not a result.json"),
    (["--vary", "l9=0.1:0.2:3"], "not free parameters: l9"),
    (["--vary", "l1=0.1:0.2"], "expected NAME=LOW:HIGH:COUNT"),
    (["--vary", "l1=0.1:0.2:3", "--scheduler", "nowhere"], "--scheduler 'nowhere'"),
    (["--vary", "l1=0.1:0.2:3", "--metric", "gci,speed"], "unknown metrics"),
    (["--vary", "l1=0.1:0.2:3", "--length", "-1"], "--length must be positive"),
])
def test_cli_bad_input_exits_with_code_2(tmp_path, capsys, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["sweep", str(GENERATED_DIR / "planar_2r"), "-o", str(tmp_path / "s.parquet"), *arguments])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "s.parquet").exists()


def test_cli_sigterm_then_resume_gives_the_uninterrupted_table(tmp_path):
    """SIGTERM mid-sweep: exit 130, the completed chunks kept; --resume finishes with the same rows."""
    import subprocess
    import time

    from conftest import SYMKIN_CLI

    command = [*SYMKIN_CLI, "sweep", str(GENERATED_DIR / "planar_2r"), "--vary", "l1=0.05:0.3:8", "--vary",
               "l2=0.05:0.3:8", "-n", "4096", "--chunk", "2", "--scheduler", "serial", "--no-figure"]
    out = tmp_path / "cut.parquet"
    process = subprocess.Popen([*command, "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    parts = tmp_path / "cut.parquet.parts"
    deadline = time.monotonic() + 60
    while not (parts.exists() and any(parts.glob("chunk-*.parquet"))) and time.monotonic() < deadline:
        time.sleep(0.05)
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "rerun the same command with --resume" in err
    kept = len(list(parts.glob("chunk-*.parquet")))
    assert 0 < kept < 32
    assert not out.exists()
    resumed = subprocess.run([*command, "-o", str(out), "--resume"], capture_output=True, text=True, check=True)
    assert f"resuming with {kept} chunks done" in resumed.stdout
    whole = tmp_path / "whole.parquet"
    subprocess.run([*command, "-o", str(whole)], capture_output=True, text=True, check=True)
    assert pq.read_table(out).equals(pq.read_table(whole))


def test_one_call_from_python_gives_the_same_table(reference, tmp_path):
    """symkin.design.sweep: from a loaded model, keyword options, a file or nothing on disk."""
    from symkin import load

    arm = load(GENERATED_DIR / "planar_2r")
    table = design.sweep(arm, vary={"l1": (0.05, 0.30, 6), "l2": (0.05, 0.30, 6)}, samples=1024, chunk=5,
                         scheduler="serial")
    assert table.equals(reference)
    design.sweep(GENERATED_DIR / "planar_2r", GRID, out=tmp_path / "g.parquet", scheduler="serial")
    assert pq.read_table(tmp_path / "g.parquet").equals(reference)
    with pytest.raises(ValueError, match="not a generated model directory"):
        design.sweep(tmp_path, GRID, scheduler="serial")

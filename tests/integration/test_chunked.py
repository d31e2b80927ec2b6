"""The GCI integrators in chunks on Dask (issue 15: budgets beyond memory).

Oracles: the planar 2R arm's workspace measure in closed form, int |det J| dq =
l1 l2 int_0^(pi/2) int_0^(pi/2) |sin theta2| dtheta1 dtheta2 = l1 l2 pi / 2, which each
estimate must meet within its own 95 % error bar (times 3: a check that fails 1 time in
~10^5 for an honest bar, not 1 in 20); the in-memory integrator's GCI, met within the two
error bars; and the chunked sum itself, which must not depend on the chunk size, on the
order the chunks ran or on the machine they ran on (bit for bit).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import GENERATED_DIR

from symkin import load
from symkin.integration import chunked
from symkin.integration.chunked import IntegrandSpec, integrate_chunked
from symkin.analysis.global_indices import gci
from symkin.cli import main
from symkin.runtime.payload import ModelPayload

pytestmark = pytest.mark.xdist_group("dask")

AREA = 0.1 * 0.1 * math.pi / 2          # l1 l2 pi / 2 at the planar arm's defaults


@pytest.fixture(scope="module")
def payload():
    return ModelPayload.from_directory(GENERATED_DIR / "planar_2r")


@pytest.mark.parametrize("method", ["qmc", "mc"])
def test_the_measure_meets_its_closed_form_and_the_gci_the_in_memory_one(payload, method):
    result = integrate_chunked(payload, IntegrandSpec(), method, 2**16, seed=4, chunk=3000, scheduler="serial")
    measure = result.component(1)
    assert abs(measure.value - AREA) <= 3 * measure.error
    reference = gci(load(GENERATED_DIR / "planar_2r"), method=method, samples=2**16, seed=4).value
    value = result.ratio(0, 1)
    assert abs(value.value - reference.value) <= 3 * (value.error + reference.error)
    assert result.evaluations == 2**16


def test_chunks_bound_the_points_of_every_task(payload, monkeypatch):
    seen = []
    original = chunked.run_tasks

    def spy(function, tasks, **options):
        seen.extend(tasks)
        return original(function, tasks, **options)

    monkeypatch.setattr(chunked, "run_tasks", spy)
    integrate_chunked(payload, IntegrandSpec(), "qmc", 2**14, chunk=100, scheduler="serial")
    assert max(stop - start for *_, start, stop in seen) <= 100
    assert sum(stop - start for *_, start, stop in seen) == 2**14             # 16 replicates of 2^10, all covered
    seen.clear()
    integrate_chunked(payload, IntegrandSpec(), "mc", 1000, chunk=300, scheduler="serial")
    assert [count for *_, count in seen] == [300, 300, 300, 100]


def test_the_sum_does_not_depend_on_scheduling(payload):
    """Bit for bit for one chunk size; another chunk size draws other digits below scipy's 30 bits (the
    generator of a chunk is seeded with its start), so it agrees within the error bars only."""
    serial = [integrate_chunked(payload, IntegrandSpec(), "qmc", 2**13, seed=2, chunk=c, scheduler="serial")
              for c in (2**9, 200)]
    local = integrate_chunked(payload, IntegrandSpec(), "qmc", 2**13, seed=2, chunk=200, scheduler="local",
                              workers=2)
    np.testing.assert_array_equal(local.values, serial[1].values)
    np.testing.assert_array_equal(local.covariance, serial[1].covariance)
    bars = 3 * (serial[0].component(1).error + serial[1].component(1).error)
    assert abs(serial[0].component(1).value - serial[1].component(1).value) <= bars
    mc = [integrate_chunked(payload, IntegrandSpec(), "mc", 5000, seed=2, chunk=1000, scheduler=s, workers=2)
          for s in ("serial", "local")]
    np.testing.assert_array_equal(mc[0].values, mc[1].values)


def test_cli_chunked_gci(capsys):
    assert main(["gci", str(GENERATED_DIR / "planar_2r"), "-n", "1e5", "--scheduler", "serial", "--chunk", "5000",
                 "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "65536 evaluations by qmc" in out
    assert "in chunks of at most 5000 points in this process" in out
    measure = float(out.split("int dW = ")[1].split()[0])
    error = float(out.split("int dW = ")[1].split()[2])
    assert abs(measure - AREA) <= 3 * error


def test_the_cartesian_domain_in_chunks(payload):
    """Reachability by inverse kinematics over a Cartesian box: the planar arm's area within its error bar, and
    the rotating Stewart platform (at its home orientation) against the in-memory integrator within both bars."""
    from symkin.analysis import inverse
    from symkin.mechanism import reach

    model = payload.load()
    box = tuple(tuple(float(v) for v in b) for b in reach.bounding_box(model))
    area = integrate_chunked(payload, IntegrandSpec(domain="cartesian", box=box), "qmc", 2**15, seed=5, chunk=5000,
                             scheduler="serial").component(1)
    assert abs(area.value - AREA) <= 3 * area.error
    stewart_payload = ModelPayload.from_directory(GENERATED_DIR / "stewart")
    held = reach.held_at(stewart_payload.load(), None)
    box = tuple(tuple(float(v) for v in b) for b in reach.bounding_box(held))
    chunked_gci = integrate_chunked(stewart_payload, IntegrandSpec(length=0.1, domain="cartesian", box=box), "qmc", 2**15,
                                    seed=6,
                                    chunk=5000, scheduler="serial").ratio(0, 1)
    in_memory = gci(held, domain="cartesian", inverse=inverse.inverse_kinematics_for(held), samples=2**15, seed=6,
                    length=0.1, box=tuple(np.array(b) for b in box))
    assert abs(chunked_gci.value - in_memory.value.value) <= 3 * (chunked_gci.error + in_memory.value.error)


@pytest.mark.parametrize("arguments, message", [
    (["--scheduler", "serial", "--map", "x.png"], "--scheduler integrates by mc or qmc (no --map)"),
    (["--scheduler", "serial", "--method", "grid"], "--scheduler integrates by mc or qmc"),
    (["--scheduler", "somewhere"], "--scheduler 'somewhere'"),
    (["-n", "1.5"], "not a whole positive number"),
])
def test_cli_chunked_bad_input_exits_with_code_2(capsys, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["gci", str(GENERATED_DIR / "planar_2r"), *arguments])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err

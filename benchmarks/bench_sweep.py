"""Design sweeps: designs per second in this process and on a Dask LocalCluster of 1 and 2 workers.

Run with `make bench` or `python benchmarks/bench_sweep.py [--designs N]`.  For the seed's
planar 2R arm and the DELTA, a Sobol set of designs (link lengths within +-40 % of the
defaults; the GCI and workspace measure of 4096 quasi-Monte Carlo points each, plus the
extreme kappas) is swept

* serially, in this process (``--scheduler serial``);
* on a LocalCluster of 1 and of 2 worker processes, already started (its start-up time is
  printed apart), each run from an empty store;

and the three tables are checked to be identical to the bit.  Also measured: the Dask
scheduler's cost per task (a thousand no-op tasks on the 2-worker cluster).  From these the
projected wall time of a 10^6-design DELTA sweep on P cores is

    T(P) = N t_design / P + (N / chunk) t_task

(t_design: the serial time per design; t_task: the scheduler's time per task, which does not
shrink with P: one scheduler hands out every task).  Speed is reported, never asserted.
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.design.sweeps import SweepAxis, SweepDefinition, evaluate_missing  # noqa: E402
from symkin.design.sweep_store import SweepStore  # noqa: E402
from symkin.runtime.payload import ModelPayload  # noqa: E402

MODELS = ("planar_2r", "delta")
CHUNK = 32
PROJECTED = 10**6
CORES = (1, 16, 256)


def definition_for(payload: ModelPayload, designs: int) -> SweepDefinition:
    """Every length parameter (unit m) varied within +-40 % of its default."""
    model = payload.load()
    lengths = [name for name in model.parameters if model.info.units.get(name) == "m"]
    axes = tuple(SweepAxis(n, 0.6 * model.parameters[n], 1.4 * model.parameters[n]) for n in lengths)
    return SweepDefinition(axes, sobol=designs, chunk=CHUNK)


def timed_sweep(payload: ModelPayload, definition: SweepDefinition, **where) -> tuple[float, object]:
    with tempfile.TemporaryDirectory() as scratch:
        start = time.perf_counter()
        store = SweepStore(Path(scratch) / "s.parquet", definition, payload)
        evaluate_missing(payload, definition, store, **where)
        return time.perf_counter() - start, store.table()


def _noop(k: int) -> int:
    return k


def main() -> None:
    from dask.distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=512, help="designs per model (default: %(default)s)")
    options = parser.parse_args()
    clusters = {}
    for workers in (1, 2):
        start = time.perf_counter()
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=logging.ERROR)
        clusters[workers] = (cluster, Client(cluster), time.perf_counter() - start)
    client = clusters[2][1]
    start = time.perf_counter()
    client.gather(client.map(_noop, range(1000), pure=False))
    per_task = (time.perf_counter() - start) / 1000
    print(f"LocalCluster start-up: 1 worker {clusters[1][2]:.2f} s, 2 workers {clusters[2][2]:.2f} s; "
          f"scheduler cost per task {per_task * 1e3:.2f} ms (1000 no-op tasks, 2 workers)")
    print(f"{'model':<10} {'designs':>7} {'serial':>14} {'1 worker':>14} {'2 workers':>14} {'2 / 1':>6}  identical")
    per_design = {}
    for name in MODELS:
        payload = ModelPayload.from_directory(ROOT / "generated" / name)
        definition = definition_for(payload, options.designs)
        timed_sweep(payload, SweepDefinition(definition.axes, sobol=CHUNK, chunk=CHUNK), scheduler="serial")
        serial, reference = timed_sweep(payload, definition, scheduler="serial")
        runs = {}
        for workers, (_, worker_client, _) in clusters.items():
            timed_sweep(payload, SweepDefinition(definition.axes, sobol=CHUNK, chunk=CHUNK), client=worker_client)
            runs[workers] = timed_sweep(payload, definition, client=worker_client)
        same = all(table.equals(reference) for _, table in runs.values())
        rates = [definition.size / t for t in (serial, runs[1][0], runs[2][0])]
        print(f"{name:<10} {definition.size:>7} " + " ".join(f"{r:>10.0f} d/s" for r in rates)
              + f" {rates[2] / rates[1]:>6.2f}  {'yes' if same else 'NO'}")
        per_design[name] = serial / definition.size
    t_design = per_design["delta"]
    projection = ", ".join(f"{p} cores {(PROJECTED * t_design / p + PROJECTED / CHUNK * per_task) / 60:.1f} min"
                           for p in CORES)
    print(f"projected 10^6-design DELTA sweep (t_design {t_design * 1e3:.2f} ms, chunks of {CHUNK}, "
          f"t_task {per_task * 1e3:.2f} ms): {projection}")
    for cluster, worker_client, _ in clusters.values():
        worker_client.close()
        cluster.close()


if __name__ == "__main__":
    main()

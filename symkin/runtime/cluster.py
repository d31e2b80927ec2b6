"""Run independent tasks on Dask, or in this process: the one scheduler of symkin's large jobs.

symkin writes no scheduler of its own.  :func:`run_tasks` hands a list of tasks to
``dask.distributed``:

* ``scheduler="local"`` (the default of the commands): a ``LocalCluster`` of ``workers``
  processes (default: one per core), one thread each (the generated numpy code holds the GIL
  between its array operations), started for the run and closed after it;
* ``scheduler="tcp://host:8786"``: the cluster whose scheduler runs there (``dask scheduler``,
  ``dask worker tcp://host:8786`` on each machine);
* ``client=``: a ``dask.distributed.Client`` the caller owns;
* ``scheduler="serial"``: in this process, in task order (no Dask).

The ``shared`` argument of every task (e.g. a :class:`~symkin.runtime.payload.ModelPayload`)
is itself a task's result, not scattered data: when every worker holding it dies, the
scheduler recomputes it.  Dask reruns the tasks of a worker that dies (``retries`` for tasks
that fail).  Results come back in completion order; callers that need a fixed order (sums)
key them by the task index they are given.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable, Iterator, Sequence
from typing import Any

#: schedulers besides an address
SCHEDULERS = ("local", "serial")


def check_scheduler(scheduler: str, workers: int | None = None) -> None:
    """Raise ValueError for a scheduler that is neither local, serial nor an address, or a bad worker count."""
    if scheduler not in SCHEDULERS and "://" not in scheduler:
        raise ValueError(f"--scheduler '{scheduler}': use local, serial or a scheduler address such as "
                         "tcp://HOST:8786")
    if workers is not None and workers < 1:
        raise ValueError("--workers must be at least 1")


@contextlib.contextmanager
def dask_client(scheduler: str = "local", workers: int | None = None) -> Iterator[Any]:
    """A ``dask.distributed.Client`` of a LocalCluster started here (``local``) or of the scheduler at an address."""
    from dask.distributed import Client, LocalCluster

    if scheduler == "local":
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
            yield client
    else:
        with Client(scheduler) as client:
            yield client


def _same(value: Any) -> Any:
    return value


def run_tasks(function: Callable[..., Any], tasks: Sequence[tuple], *, shared: Any, name: str,
              finished: Callable[[int, Any], None], scheduler: str = "local", workers: int | None = None,
              client: Any = None, started: Callable[[], None] = lambda: None) -> None:
    """Evaluate ``function(shared, *task)`` for every task; ``finished(i, result)`` runs here as task i completes.

    Args:
        name: a prefix of the task keys (unique per job: e.g. with the payload's digest).
        started: called once the workers are ready, before the first result.
        scheduler, workers, client: where the tasks run (see the module docstring).
    """
    if client is None and scheduler == "serial":
        started()
        for i, task in enumerate(tasks):
            finished(i, function(shared, *task))
        return
    with contextlib.nullcontext(client) if client is not None else dask_client(scheduler, workers) as active:
        from dask.distributed import as_completed

        started()
        shared_future = active.submit(_same, shared, key=f"{name}-shared")
        futures = {active.submit(function, shared_future, *task, key=f"{name}-{i}", retries=2): i
                   for i, task in enumerate(tasks)}
        try:
            for future in as_completed(futures):
                finished(futures[future], future.result())
        finally:
            active.cancel(list(futures))

"""``symkin.design.sweep(...)``: a whole design sweep from Python in one call (what ``symkin sweep`` runs).

    table = symkin.design.sweep("generated/planar_2r", vary={"l1": (0.05, 0.3, 12), "l2": (0.05, 0.3, 12)})
    table = symkin.design.sweep(model, definition, client=client, out="sweep.parquet", resume=True)

It builds the :class:`~symkin.design.sweeps.SweepDefinition` (unless given one), the
:class:`~symkin.runtime.payload.ModelPayload` of the model and the
:class:`~symkin.design.sweep_store.SweepStore` (``out``, or a scratch store), evaluates the
missing chunks (:func:`~symkin.design.sweeps.evaluate_missing`) and returns the pyarrow table,
sorted by design, with the sweep's metadata.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from symkin.design.sweep_store import SweepStore
from symkin.design.sweeps import DEFAULT_METRICS, SweepAxis, SweepDefinition, evaluate_missing
from symkin.runtime.payload import PAYLOAD_BACKENDS, ModelPayload


def _payload(model: Any) -> ModelPayload:
    if isinstance(model, ModelPayload):
        return model
    directory = Path(getattr(model, "directory", model))
    if not (directory / "manifest.json").exists():
        raise ValueError(f"{directory}: not a generated model directory (derive it with 'symkin derive', or pass "
                         "the directory of symkin.load)")
    backend = getattr(model, "backend", "numpy")     # a model loaded with JAX sweeps on JAX
    return ModelPayload.from_directory(directory, backend if backend in PAYLOAD_BACKENDS else "numpy")


def sweep(model: Any, definition: SweepDefinition | None = None, *,
          vary: Mapping[str, Sequence[float]] | None = None, sobol: int | None = None,
          metrics: Sequence[str] = DEFAULT_METRICS, samples: int = 4096, seed: int = 0, chunk: int = 64,
          fixed: Mapping[str, float] | None = None, length: float | str = "auto", out: str | Path | None = None,
          resume: bool = False,
          scheduler: str = "local", workers: int | None = None, client: Any = None,
          progress: Callable[[int, int], None] = lambda done, total: None) -> Any:
    """Evaluate a design sweep and return its table (pyarrow; see :mod:`symkin.design.sweeps`).

    Args:
        model: a generated model directory, a model loaded from one (``symkin.load``), or a
            :class:`~symkin.runtime.payload.ModelPayload`.
        definition: the sweep; or give ``vary`` ({name: (low, high, count)} for a grid,
            {name: (low, high)} with ``sobol``) and the other fields (``length``: the characteristic length
            of a task space mixing translations and rotations, m or ``"auto"``; :class:`SweepDefinition`).
        out: the Parquet file to write (with ``resume``, continue the interrupted sweep of
            the same definition there); None: nothing is kept on disk.
        scheduler, workers, client: where the chunks run: ``local`` (a LocalCluster),
            ``serial`` (this process), a scheduler address, or a ``dask.distributed.Client``.
        progress: called with (designs done, designs in all).
    """
    if definition is None:
        if not vary:
            raise ValueError("sweep: give a SweepDefinition or the parameters to vary")
        axes = tuple(SweepAxis(name, float(r[0]), float(r[1]), None if sobol is not None else int(r[2]))
                     for name, r in vary.items())
        definition = SweepDefinition(axes, tuple(metrics), sobol, samples, seed, chunk,
                                     tuple(sorted((fixed or {}).items())), length)
    payload = _payload(model)
    with tempfile.TemporaryDirectory(prefix="symkin-sweep-") as scratch:
        store = SweepStore(out if out is not None else Path(scratch) / "sweep.parquet", definition, payload,
                           resume=resume)
        evaluate_missing(payload, definition, store, scheduler=scheduler, workers=workers, client=client,
                         progress=progress)
        return store.finish()

"""Where a sweep's results live while it runs and when it is done: nothing lost, nothing twice.

A sweep writing ``OUT.parquet`` keeps ``OUT.parquet.parts/`` while it runs: ``sweep.json``
(the definition and the model it belongs to) and one Parquet file per completed chunk,
``chunk-000012.parquet``, each written under a temporary name and renamed into place, so a
part is either complete or absent whatever interrupts the run (Ctrl-C, SIGTERM, a killed
machine).  ``--resume`` reopens the parts of the same definition and model and evaluates
only the missing chunks; a part is keyed by its chunk, so no design can appear twice.  When
every chunk is in, the table (sorted by design) is written to ``OUT.parquet`` with the
model hash, the symkin version and the sweep definition in its schema metadata, and the parts
directory goes.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import Any

from symkin._version import __version__
from symkin.atomic import replace_file
from symkin.design.sweeps import SweepDefinition
from symkin.runtime.payload import ModelPayload

PART = re.compile(r"chunk-(\d{6})\.parquet")


def schema(definition: SweepDefinition) -> Any:
    """The Arrow schema of a result row (see :meth:`SweepDefinition.columns`)."""
    import pyarrow as pa

    fields = [pa.field("design", pa.int64())]
    fields += [pa.field(name, pa.float64()) for name in definition.columns()[1:-1]]
    return pa.schema(fields + [pa.field("status", pa.string())])


class SweepStore:
    """The results of one sweep (see the module docstring).

    Args:
        output: the result file (``.parquet``).
        definition: the sweep.
        payload: the model (its name and hash go into the metadata and ``sweep.json``).
        resume: reuse the completed chunks of an interrupted sweep of the same definition and
            model; otherwise any earlier parts are discarded.

    Raises:
        ValueError: ``resume`` and the parts belong to another definition or model.
    """

    def __init__(self, output: str | Path, definition: SweepDefinition, payload: ModelPayload, *,
                 resume: bool = False):
        self.output = Path(output)
        self.parts = self.output.with_name(self.output.name + ".parts")
        self.definition = definition
        self.identity = {"model": payload.name, "model_hash": payload.model_hash, "backend": payload.backend,
                         "sweep": json.loads(definition.to_json())}
        stamp = self.parts / "sweep.json"
        if resume and stamp.exists():
            found = json.loads(stamp.read_text())
            if found != self.identity:
                raise ValueError(f"--resume: {self.parts} holds a sweep of another definition or model "
                                 f"({found.get('model')}, {found.get('model_hash', '')[:19]}...); rerun with "
                                 "the same options, or without --resume to start over")
        else:
            shutil.rmtree(self.parts, ignore_errors=True)
            self.parts.mkdir(parents=True)
            replace_file(stamp, json.dumps(self.identity, sort_keys=True, indent=1) + "\n")

    def completed(self) -> set[int]:
        """The chunks whose results are stored."""
        return {int(m.group(1)) for p in self.parts.iterdir() if (m := PART.fullmatch(p.name))}

    def write_chunk(self, chunk: int, columns: dict[str, list]) -> None:
        """Store one chunk's rows (atomically: the part is complete or absent)."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.Table.from_pydict(columns, schema=schema(self.definition))
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        replace_file(self.parts / f"chunk-{chunk:06d}.parquet", sink.getvalue().to_pybytes())

    def table(self) -> Any:
        """Every stored row, sorted by design, with the sweep's metadata."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        parts = [pq.read_table(self.parts / f"chunk-{k:06d}.parquet") for k in sorted(self.completed())]
        table = pa.concat_tables(parts) if parts else schema(self.definition).empty_table()
        table = table.sort_by("design")
        metadata = {"symkin.version": __version__, "symkin.model": self.identity["model"],
                    "symkin.model_hash": self.identity["model_hash"], "symkin.sweep": self.definition.to_json()}
        return table.replace_schema_metadata({k: v.encode() for k, v in metadata.items()})

    def finish(self) -> Any:
        """Write the result file (every chunk must be in) and remove the parts; returns the table."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        missing = self.definition.chunks - len(self.completed())
        if missing:
            raise RuntimeError(f"{missing} chunks of the sweep are not stored yet")
        table = self.table()
        sink = pa.BufferOutputStream()
        pq.write_table(table, sink)
        replace_file(self.output, sink.getvalue().to_pybytes())
        shutil.rmtree(self.parts, ignore_errors=True)
        return table


def read_sweep(path: str | Path) -> tuple[Any, SweepDefinition, dict[str, str]]:
    """(table, definition, metadata) of a result file."""
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    metadata = {k.decode(): v.decode() for k, v in (table.schema.metadata or {}).items()}
    if "symkin.sweep" not in metadata:
        raise ValueError(f"{path}: not a symkin sweep (no 'symkin.sweep' in its Parquet metadata)")
    return table, SweepDefinition.from_json(metadata["symkin.sweep"]), metadata


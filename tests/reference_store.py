"""Sampled inputs and reference values that ``make test``'s two passes share (Makefile: SYMKIN_TEST_REFERENCES).

The references of tests/backends/test_backends_agree.py are exact symbolic work: each generated function's
un-optimized expressions, derived and lambdified, evaluated at random states near the model's home assembly.  The
foreign-arithmetic pass (tests/conftest.py) would derive, print and evaluate them again - half of that pass's time -
to compare its generated code, evaluated on foreign arithmetic, with the same values.  So the first pass writes
them into a folder made for one ``make test`` and the second reads them: the generated code under test is still
evaluated on each pass's arithmetic, against references computed once (rounded on native arithmetic, within the
agreement bound like any reference).  Without the variable (a bare pytest run) every test computes its own.

An entry is keyed by the model, the sampling (seed, points) and the SHA-256 of the generated code's manifest,
written under a temporary name and renamed into place (two workers may compute the same entry; either copy serves).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

#: The folder the passes share (unset: nothing is stored).
STORE = os.environ.get("SYMKIN_TEST_REFERENCES")


def stored(key: str, compute: Callable[[], dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The arrays ``compute()`` gives, read from the store where an earlier pass wrote them under ``key``."""
    if not STORE:
        return compute()
    path = Path(STORE) / f"{key}.npz"
    if path.is_file():
        with np.load(path) as data:
            return {name: data[name] for name in data.files}
    arrays = compute()
    partial = path.with_name(f".{key}.{os.getpid()}.partial")
    with open(partial, "wb") as file:
        np.savez(file, **arrays)
    os.replace(partial, path)
    return arrays


def manifest_key(directory: Path, *parts: object) -> str:
    """A store key of the generated code in ``directory`` and the sampling ``parts``."""
    digest = hashlib.sha256((directory / "manifest.json").read_bytes()).hexdigest()[:16]
    return "-".join([directory.name, *map(str, parts), digest])

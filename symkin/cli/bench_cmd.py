"""``symkin bench KIND MODEL``: measured figures (run time against error, numerical stability...).

Each kind lives in its own module exposing ``register(subparsers)``; list it in :data:`KINDS`.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from symkin.cli import bench_gci, bench_stability

#: Registration functions of the benchmark kinds (``symkin bench gci``, ``symkin bench stability``...).
KINDS: list[Callable[[argparse._SubParsersAction], None]] = [
    bench_gci.register,
    bench_stability.register,
]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="benchmarks: run time against error, numerical stability",
                       description="Measure and report (tables and figures); nothing is asserted.")
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)
    for register_kind in KINDS:
        register_kind(kinds)
    if not KINDS:
        p.set_defaults(run=lambda _args: p.error("no benchmark kinds are available"))

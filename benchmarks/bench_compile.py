"""Compile time of the generated C libraries, with and without GCC's SLP vectorizer.

Run with `make bench` or `python benchmarks/bench_compile.py [--models NAMES] [--flags SETS]`.

Each model of ``generated/`` is built exactly as ``load(..., backend="c")`` builds it
(:func:`symkin.backends.c.build.shared_library`, into an empty temporary cache so nothing is
reused), once per set of ``SYMKIN_CFLAGS``.  The default sets are the default ``-O3`` and
``-O3 -fno-tree-slp-vectorize``: GCC's SLP vectorizer dominates the build of large lane
loops, which is why functions with many outputs batch by single calls (``LANE_SLOTS``, see
docs/generated-code.md).  Each build is timed twice: with one compiler process
(``SYMKIN_BUILD_JOBS=1``, the translation units one after the other) and with one per core
(the default), so the gain of compiling the source's translation units in parallel is a
ratio measured in the same run.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.backends.c.build import build_jobs, shared_library, translation_units  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

GENERATED = ROOT / "generated"
DEFAULT_FLAGS = ("-O3", "-O3 -fno-tree-slp-vectorize")


def build_seconds(source: Path, flags: str, jobs: int) -> float:
    """Wall time of one uncached build of ``source`` with ``SYMKIN_CFLAGS=flags`` and ``jobs`` compilers."""
    saved = {key: os.environ.get(key) for key in ("SYMKIN_CFLAGS", "SYMKIN_CACHE_DIR", "SYMKIN_BUILD_JOBS")}
    with tempfile.TemporaryDirectory(prefix="symkin-bench-compile-") as cache:
        os.environ.update(SYMKIN_CFLAGS=flags, SYMKIN_CACHE_DIR=cache, SYMKIN_BUILD_JOBS=str(jobs))
        try:
            start = time.perf_counter()
            shared_library(source, source.with_suffix(".h"))
            return time.perf_counter() - start
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", default="planar_2r,ur10e,delta,stewart",
                        help="comma-separated directories of generated/ (default: %(default)s)")
    parser.add_argument("--flags", action="append", default=None, metavar="CFLAGS",
                        help="a set of SYMKIN_CFLAGS to time (repeatable; default: " + " and ".join(
                            repr(f) for f in DEFAULT_FLAGS) + ")")
    args = parser.parse_args(argv)
    flag_sets = args.flags or list(DEFAULT_FLAGS)
    cores = build_jobs()
    rows = []
    for name in filter(None, (m.strip() for m in args.models.split(","))):
        source = GENERATED / name / f"{name}.c"
        if not source.exists():
            parser.error(f"{source} does not exist; derive the model with the c backend (make generate)")
        size = source.stat().st_size / 1024
        units = len(translation_units(source.read_text()))
        for flags in flag_sets:
            print(f"  building {name} with {flags!r} ...", flush=True)
            serial, parallel = build_seconds(source, flags, 1), build_seconds(source, flags, cores)
            rows.append([name, f"{size:.0f}", units, flags, f"{serial:.1f}", f"{parallel:.1f}",
                         f"{serial / parallel:.2f}"])
    print("C compile time of the generated libraries (uncached, as load(..., backend='c') builds them)")
    print(format_table(["model", "source [kB]", "units", "SYMKIN_CFLAGS", "build, 1 job [s]",
                        f"build, {cores} jobs [s]", "speed-up"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())

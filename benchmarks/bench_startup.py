"""Start-up of the command line (issue 34): `symkin --help` and a numeric command on generated code, against the
interpreter importing numpy alone, each the median of several fresh processes; and `symkin derive` of the UR10e
without the derivation cache against a repeated derive that finds it there.

Run with `make bench` or `python benchmarks/bench_startup.py [--repeat N]`.  Targets: `symkin --help` at most
0.15 s more than `python -c "import numpy"`; a repeated derive at most 25 % of the first.
"""

from __future__ import annotations

import argparse
import statistics
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.text_table import format_table  # noqa: E402

COMMANDS = {
    "python -c 'import numpy'": [sys.executable, "-c", "import numpy"],
    "symkin --help": [sys.executable, "-m", "symkin", "--help"],
    "symkin gci generated/planar_2r -n 1000": [sys.executable, "-m", "symkin", "gci",
                                               str(ROOT / "generated" / "planar_2r"), "-n", "1000"],
}


def median_seconds(command: list[str], repeat: int, env: dict[str, str] | None = None) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, env=env)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def derive_times(repeat: int) -> dict[str, float]:
    """The UR10e derived afresh (--no-cache) and again from a cache that holds it (a scratch cache directory)."""
    with tempfile.TemporaryDirectory() as scratch:
        env = {**os.environ, "SYMKIN_CACHE_DIR": str(Path(scratch) / "cache")}
        derive = [sys.executable, "-m", "symkin", "derive", str(ROOT / "models" / "ur10e.yaml"), "-o",
                  str(Path(scratch) / "out"), "-q"]
        first = median_seconds(derive + ["--no-cache"], max(1, repeat // 3), env)
        subprocess.run(derive, check=True, capture_output=True, env=env)  # fills the cache
        return {"symkin derive models/ur10e.yaml (no cache)": first,
                "symkin derive models/ur10e.yaml (repeated: cache hit)": median_seconds(derive, repeat, env)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    times = {name: median_seconds(command, args.repeat) for name, command in COMMANDS.items()}
    floor = times["python -c 'import numpy'"]
    print(format_table(["command", "median", "beyond numpy's import"],
                       [[name, f"{t:.3f} s", f"{t - floor:+.3f} s"] for name, t in times.items()]))
    print("target: symkin --help <= +0.150 s")
    derives = derive_times(args.repeat)
    first, repeated = derives.values()
    print(format_table(["command", "median", "of the first"],
                       [[name, f"{t:.3f} s", f"{100 * t / first:.0f} %"] for name, t in derives.items()]))
    print(f"target: a repeated derive <= 25 % of the first (here {100 * repeated / first:.0f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

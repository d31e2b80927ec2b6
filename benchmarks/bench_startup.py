"""Start-up of the command line (issue 34): `symkin --help` and a numeric command on generated code, against the
interpreter importing numpy alone, each the median of several fresh processes; and `symkin derive` of the UR10e
without the derivation cache against a repeated derive that finds it there.

Run with `make bench` or `python benchmarks/bench_startup.py [--repeat N]`.  Targets: `symkin --help` at most
0.15 s more than `python -c "import numpy"`; a repeated derive at most 25 % of the first.

Every command runs as an installed program starts: from compiled bytecode.  pip compiles a wheel's modules when it
installs them, so numpy's bytecode is on disk; symkin's modules in an editable checkout are compiled on first
import and, where ``PYTHONDONTWRITEBYTECODE`` is set (as on the machines this project is developed on), compiled
again in every process, which added about 0.1 s to `symkin --help` and nothing to numpy's import.  The commands
therefore run with bytecode writing on, the bytecode kept in a scratch directory (``PYTHONPYCACHEPREFIX``: the
checkout is not touched), after one untimed run that fills it.
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


def bytecode_environment(scratch: str) -> dict[str, str]:
    """The environment of an installed program: bytecode read and written (in ``scratch``, not the checkout)."""
    env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
    return {**env, "PYTHONPYCACHEPREFIX": str(Path(scratch) / "bytecode")}


def median_seconds(command: list[str], repeat: int, env: dict[str, str]) -> float:
    """The median wall time of ``repeat`` runs of ``command``, after one untimed run (which compiles the bytecode)."""
    subprocess.run(command, check=True, capture_output=True, env=env)
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, env=env)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def derive_times(repeat: int) -> dict[str, float]:
    """The UR10e derived afresh (--no-cache) and again from a cache that holds it (a scratch cache directory)."""
    with tempfile.TemporaryDirectory() as scratch:
        env = {**bytecode_environment(scratch), "SYMKIN_CACHE_DIR": str(Path(scratch) / "cache")}
        derive = [sys.executable, "-m", "symkin", "derive", str(ROOT / "models" / "ur10e.yaml"), "-o",
                  str(Path(scratch) / "out"), "-q"]
        first = median_seconds(derive + ["--no-cache"], max(1, repeat // 3), env)
        return {"symkin derive models/ur10e.yaml (no cache)": first,
                "symkin derive models/ur10e.yaml (repeated: cache hit)": median_seconds(derive, repeat, env)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as scratch:
        env = bytecode_environment(scratch)
        times = {name: median_seconds(command, args.repeat, env) for name, command in COMMANDS.items()}
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

"""Start-up of the command line (issue 34): `symkin --help` and a numeric command on generated code, against the
interpreter importing numpy alone, each the median of several fresh processes.

Run with `make bench` or `python benchmarks/bench_startup.py [--repeat N]`.  Target: `symkin --help` at most
0.15 s more than `python -c "import numpy"`.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
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


def median_seconds(command: list[str], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    times = {name: median_seconds(command, args.repeat) for name, command in COMMANDS.items()}
    floor = times["python -c 'import numpy'"]
    print(format_table(["command", "median", "beyond numpy's import"],
                       [[name, f"{t:.3f} s", f"{t - floor:+.3f} s"] for name, t in times.items()]))
    print("target: symkin --help <= +0.150 s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Excitation (issue 33): `symkin excite` on the example models with the options docs/identification.md quotes (and
docs/model-format.md's dual SCARA, legs without the distance form) -
cond(W S) of the stacked, column-scaled base regressor at the start and at the end, IPOPT's status and the wall
time of the command (start-up and derivation of the model file included, the derivation cache empty: what a user
waits for the first time).

The start is the series of :mod:`symkin.identification.excitation` at its seed, so the figures are reproducible; the
end depends on IPOPT's path (its iterations' floating point), so the documented figures are rounded ("about").
Run with `make bench` or `python benchmarks/bench_excitation.py [--models planar_2r,stewart]`.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from documented_models import DOCUMENTED, model_text  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

#: model -> the options of `symkin excite` that docs/identification.md quotes for it.
CASES = {
    "planar_2r": "--max-velocity 2 --max-acceleration 10 --period 4 --harmonics 4 --periods 3",
    "ur10e": "--max-velocity 1 --max-acceleration 3 --period 10 --harmonics 5 --periods 3 --max-iterations 100",
    "delta": "--max-velocity 3 --max-acceleration 20 --period 4 --harmonics 3",
    "delta_wrist": "--max-velocity 3 --max-acceleration 20 --period 4 --harmonics 2 --max-iterations 15",
    "stewart": "--max-velocity 0.1 --max-acceleration 1 --period 4 --harmonics 2 --max-iterations 10",
    # docs/model-format.md's dual SCARA (legs without the distance form), its actuators within 0.3 rad and 0.05 m of
    # the home assembly (theta1, lift1, phi2, knee2 = 0.489, 0.1, -3.630, -1.834), as its test gives them
    "dual_scara": "--limit theta1=0.189:0.789 --limit lift1=0.05:0.15 --limit phi2=-3.930:-3.330 "
                  "--limit knee2=-2.134:-1.534 --max-velocity 1 --max-acceleration 10 --period 4 --harmonics 3 "
                  "--max-iterations 30",
}


def excite(name: str, options: str, directory: Path) -> list[str]:
    """One row: the model, its options, cond at the start and the end, IPOPT's status, the wall time."""
    out = directory / name
    model = ROOT / "models" / f"{name}.yaml"
    if name in DOCUMENTED:  # a model of the documents, written out as they write it
        model = directory / f"{name}.yaml"
        model.write_text(model_text(name))
    environment = dict(os.environ, SYMKIN_CACHE_DIR=str(directory / "cache"))  # derived afresh, as on first use
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "symkin", "excite", str(model), *options.split(),
                    "--no-figure", "-o", str(out)], check=True, capture_output=True, env=environment)
    elapsed = time.perf_counter() - start
    record = json.loads((out / "excitation.json").read_text())
    return [name, options, f"{record['condition_start']:.4g}", f"{record['condition']:.4g}", record["ipopt_status"],
            f"{elapsed:.1f} s"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", default=",".join(CASES), help="comma-separated models (default: %(default)s)")
    args = parser.parse_args(argv)
    names = args.models.split(",")
    unknown = [name for name in names if name not in CASES]
    if unknown:
        parser.error(f"no excitation case for {', '.join(unknown)}; choose among {', '.join(CASES)}")
    with tempfile.TemporaryDirectory() as scratch:
        rows = [excite(name, CASES[name], Path(scratch)) for name in names]
    print(format_table(["model", "symkin excite options", "cond start", "cond end", "IPOPT", "time"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())

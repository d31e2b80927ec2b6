"""Cost of passive-joint limits in the DELTA's workspace and GCI analyses.

Run with `make bench` or `python benchmarks/bench_passive.py [--samples N]`.

The example DELTA (models/delta.yaml) is derived with and without
``elbow_limits: [null, [-w, w]]`` (numpy backend, the scene the analyses need).  With
limits, every assembled pose also needs its passive joint variables, found by damped
Gauss-Newton on the generated loop closure (symkin.mechanism.passive); without, the closed
forms alone decide.  Printed: the time of the working-mode test per pose and of a GCI
(joint-domain grid) with each limit, and the workspace volume, side by side in this process.
The per-pose figure and the table of docs/analysis.md ("Passive-joint limits") come from here.
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin.numerics import sampling  # noqa: E402
from symkin.analysis import global_indices  # noqa: E402
from symkin.mechanism import reach  # noqa: E402
from symkin.mechanism.working_mode import working_mode
from symkin import mechanism
from symkin.text_table import format_table  # noqa: E402

WIDTHS_DEG = (None, 40, 30, 20, 10)
SCENE = "scene:\n  outputs: [ik, fk, jacobian, closure, closure_jacobians]\n  backends: [numpy]\n"


def delta_with_elbow_limits(width_deg: float | None, directory: Path):
    """The example DELTA, its elbows' sideways swing limited to +-width_deg (None: no limit), derived and loaded."""
    text = re.sub(r"scene:.*", SCENE, (ROOT / "models" / "delta.yaml").read_text(), flags=re.S)
    if width_deg is not None:
        text = text.replace("actuator_limits: [deg(-90), deg(60)]", "actuator_limits: [deg(-90), deg(60)]\n"
                            f"    elbow_limits: [null, [deg(-{width_deg}), deg({width_deg})]]")
    path = directory / f"delta_{width_deg}.yaml"
    path.write_text(text)
    return symkin.load(symkin.derive(path, directory / f"generated_{width_deg}"))


def seconds(function) -> tuple[float, object]:
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=20_000, help="joint-grid samples of the GCI (default: 20000)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix="symkin-bench-passive-") as scratch:
        for width in WIDTHS_DEG:
            model = delta_with_elbow_limits(width, Path(scratch))
            box = mechanism.joint_limits(model)
            q = sampling.grid(box[:, 0], box[:, 1], 16)  # 16^3 configurations
            mode_time, (_, inside) = seconds(lambda: working_mode(model, q))
            gci_time, joint = seconds(lambda: global_indices.gci(model, method="grid", samples=args.samples))
            cartesian = global_indices.gci(model, method="grid", samples=args.samples, domain="cartesian",
                                           box=reach.bounding_box(model), inverse=reach.generated_inverse(model))
            rows.append(["none" if width is None else f"+-{width} deg", f"{1e6 * mode_time / len(q):.1f}",
                         f"{int(inside.sum())}/{len(q)}", f"{gci_time:.2f}", f"{joint.measure.value:.6f}",
                         f"{cartesian.measure.value:.6f}", f"{joint.value.value:.4f}"])
    print(f"DELTA, elbow swing limits (grid GCI, {args.samples} samples, numpy; time of the joint-domain GCI)")
    print(format_table(["elbow limit", "working mode [us/pose]", "in mode", "GCI [s]", "volume, joint [m^3]",
                        "volume, Cartesian [m^3]", "GCI (joint)"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())

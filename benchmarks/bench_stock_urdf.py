"""Load and derive time per stock robot file (issue 29): every serial arm of ``example-robot-data``
as shipped, and the arms of its humanoid and mobile manipulators whose constant frames (lumped
covers, adapters at angles such as -2.0679 rad) once made the derivation hang.

For each file: the time to read it into a model, to derive fk + jacobian, and to derive fk through
inverse_dynamics (a fresh derivation graph each, numpy backend, nothing written).  Targets of the
issue on 2 cores: <= 10 s for fk + jacobian and <= 30 s for the dynamics.

Run with ``make bench`` or ``python benchmarks/bench_stock_urdf.py [--only NAME ...]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from importlib.metadata import distribution
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin import pipeline  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

ROBOTS = Path(distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))

#: (name, file under robots/, the tip of the chain (--chain) or None for the whole tree, joints locked off the chain).
STOCK = [
    ("panda", "panda_description/urdf/panda.urdf", "panda_link8", {}),
    ("z1", "z1_description/urdf/z1.urdf", "link06", {}),
    ("ur3", "ur_description/urdf/ur3_robot.urdf", "tool0", {}),
    ("ur5", "ur_description/urdf/ur5_robot.urdf", "tool0", {}),
    ("ur10", "ur_description/urdf/ur10_robot.urdf", "tool0", {}),
    ("kinova", "kinova_description/robots/kinova.urdf", "j2s6s200_end_effector", {}),
    ("talos arm", "talos_data/robots/talos_left_arm.urdf", "arm_left_7_link", {}),
    ("baxter arm", "baxter_description/urdf/baxter.urdf", "left_hand_link", {}),
    ("so100", "so_arm_description/urdf/so100.urdf", None, {}),
    ("so101", "so_arm_description/urdf/so101.urdf", None, {}),
    ("xarm7", "xarm_description/urdf/xarm7.urdf", None, {}),
    ("tiago arm", "tiago_description/robots/tiago.urdf", "arm_tool_link", {}),
    ("tiago pro arm", "tiago_pro_description/robots/tiago_pro.urdf", "arm_left_tool_link", {}),
    # issue 29's second hang: 10 joints from the torso to the left hand, the right elbow as the issue locked it
    ("icub arm", "icub_description/robots/icub_reduced.urdf", "l_hand_dh_frame", {"r_elbow": 1.0}),
]

KINEMATICS = ("fk", "jacobian")
DYNAMICS = KINEMATICS + ("mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics")


def _derive(path: Path, tip: str | None, locks: dict[str, float], outputs: tuple[str, ...]) -> tuple[float, int]:
    """(seconds, operations after CSE) to derive and optimize ``outputs`` from a freshly read model."""
    model = load_model(path, tip=tip, locks=locks, chain=tip is not None)
    start = time.perf_counter()
    result = pipeline.generate(model, pipeline.resolve_request(model, only=outputs, backends="numpy", combine="none"))
    return time.perf_counter() - start, sum(r.op_counts["cse"] for r in result.reports)


def measure(path: Path, tip: str | None, locks: dict[str, float]) -> list[str]:
    start = time.perf_counter()
    model = load_model(path, tip=tip, locks=locks, chain=tip is not None)
    load = time.perf_counter() - start
    kinematics, kinematics_ops = _derive(path, tip, locks, KINEMATICS)
    dynamics, dynamics_ops = _derive(path, tip, locks, DYNAMICS)
    return [str(len(model.joints)), f"{load:.2f}", f"{kinematics:.2f}", str(kinematics_ops), f"{dynamics:.2f}",
            str(dynamics_ops)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="*", default=None, help="names of the table's rows to run")
    args = parser.parse_args(argv)
    rows = []
    for name, file, tip, locks in STOCK:
        if args.only and name not in args.only:
            continue
        rows.append([name, tip or "(default)"] + measure(ROBOTS / file, tip, locks))
        print(f"  {name}: done", file=sys.stderr, flush=True)
    print("stock robot files: read, derive fk + jacobian, derive fk .. inverse_dynamics (s; numpy; ops after CSE)")
    print(format_table(["robot", "tip", "joints", "read s", "fk+J s", "fk+J ops", "dynamics s", "dynamics ops"],
                       rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

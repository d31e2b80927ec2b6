"""Record Robotics Toolbox for Python's own dynamics of its Puma 560 and Stanford arm, and the kinematics of its
Kinova Jaco (a flipped joint), for tests/references/test_rtb_reference.py.

RTB is not a test dependency (it pins its own stack): its numbers are recorded here, with the script that
produced them. Run it in a virtual environment of its own:

    python -m venv /tmp/rtb && /tmp/rtb/bin/pip install roboticstoolbox-python==1.5.0
    /tmp/rtb/bin/python tests/reference/record_rtb.py > tests/reference/rtb_arms.json

It writes, for each arm and at seeded random states within the joint limits, RTB's rne (M qdd + V + G
with the motors' G^2 Jm qdd and the joint friction), inertia (M with G^2 Jm), gravload (G), coriolis
(C, as C qd) and friction, and for the Jaco fkine and jacob0, every float as Python prints it
(shortest round-trip).
"""

from __future__ import annotations

import json
import sys

import numpy as np
import roboticstoolbox as rtb

STATES = 5


def record(robot) -> list[dict]:
    rng = np.random.default_rng(30)
    lower, upper = robot.qlim
    rows = []
    for _ in range(STATES):
        q = rng.uniform(lower, upper)
        qd, qdd = rng.uniform(-1, 1, robot.n), rng.uniform(-1, 1, robot.n)
        rows.append({"q": q.tolist(), "qd": qd.tolist(), "qdd": qdd.tolist(),
                     "rne": robot.rne(q, qd, qdd).tolist(), "inertia": robot.inertia(q).tolist(),
                     "gravload": robot.gravload(q).tolist(), "coriolis_qd": (robot.coriolis(q, qd) @ qd).tolist(),
                     "friction": robot.friction(qd).tolist()})
    return rows


def record_kinematics(robot) -> list[dict]:
    """fkine and jacob0 at seeded states within +-pi (the Jaco declares no limits)."""
    rng = np.random.default_rng(31)
    rows = []
    for _ in range(STATES):
        q = rng.uniform(-np.pi, np.pi, robot.n)
        rows.append({"q": q.tolist(), "fkine": robot.fkine(q).A.tolist(), "jacob0": robot.jacob0(q).tolist()})
    return rows


json.dump({"source": f"roboticstoolbox-python {rtb.__version__}, numpy {np.__version__}",
           "puma560": record(rtb.models.DH.Puma560()), "stanford": record(rtb.models.DH.Stanford()),
           "jaco": record_kinematics(rtb.models.DH.Jaco())},
          sys.stdout, indent=1)
sys.stdout.write("\n")

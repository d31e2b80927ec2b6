"""Sample models shared by test modules (issue 35: one place, not defined in one test module and imported by
another).  Those the documentation declares are read from it, so the tests check the model a reader sees; the
others are written here, each for what the example models do not exercise."""

from __future__ import annotations

import re
from importlib.metadata import distribution
from pathlib import Path

from conftest import MODELS_DIR, ROOT

MODEL_FORMAT = ROOT / "docs" / "model-format.md"


def dual_scara_text() -> str:
    """The dual SCARA of docs/model-format.md ("Legs of any topology"): two SCARA legs R-R-P-R carrying a bar, a
    Schoenflies platform (x, y, z, yaw) whose legs have no distance form; its lifts declare no limits."""
    match = re.search(r"cat > out/dual_scara.yaml <<'EOF_MODEL'\n(.*?)^EOF_MODEL$", MODEL_FORMAT.read_text(), re.S | re.M)
    assert match, "docs/model-format.md lost the dual SCARA"
    return match.group(1)


def closure_delta_text() -> str:
    """The DELTA with its parallelograms written as revolute pairs (docs/model-format.md, "A parallelogram in a
    leg"): legs without the distance form, analysed through their loop closure."""
    match = re.search(r"cat > out/closure_delta.yaml <<'EOF_MODEL'\n(.*?)^EOF_MODEL$", MODEL_FORMAT.read_text(),
                      re.S | re.M)
    assert match, "docs/model-format.md lost the closure DELTA"
    return match.group(1)


def dual_scara_dynamics_text() -> str:
    """The dual SCARA with its link bodies, bar and rotors (docs/model-format.md, after "Legs of any topology"): the
    model above with the gravity and bodies the document appends to it."""
    match = re.search(r"<<'EOF_BODIES'\n(.*?)^EOF_BODIES$", MODEL_FORMAT.read_text(), re.S | re.M)
    assert match, "docs/model-format.md lost the dual SCARA's bodies"
    return dual_scara_text() + match.group(1)


PLANAR = (MODELS_DIR / "planar_2r.yaml").read_text()
PARAMETERS = "  g: {value: 9.81, unit: m/s^2, doc: gravitational acceleration}\n"
#: The 2R arm with a drive on each joint and friction on both (one smoothed).
DRIVEN = PLANAR.replace(PARAMETERS, PARAMETERS + "  J1: 1.2e-6\n  N1: 13.3\n  J2: 3.4e-6\n  b1: 0.1\n  c2: 0.3\n") + """
actuators:
  theta1: {rotor_inertia: J1, gear_ratio: N1}
  theta2: {rotor_inertia: J2}
friction:
  theta1: {viscous: b1, coulomb: 0.2}
  theta2: {coulomb: c2, smoothing_velocity: 0.01}
"""

#: A planar arm with distributed rigid links, viscous and smooth Coulomb friction, and
#: gravity with a component along every axis: exercises what the example models do not.
FRICTION_ARM = """
name: friction_arm
parameters:
  l1: 0.3
  l2: 0.25
  v_s: {value: 0.05, unit: rad/s, doc: Coulomb smoothing velocity}
  g: 9.81
serial:
  chain:
    - {name: j1, axis: [0, 0, 1]}
    - {name: j2, axis: [0, 1, 0], origin: {xyz: [l1, 0, 0]}}
    - {name: j3, type: P, axis: [1, 0, 0], origin: {xyz: [l2, 0, 0], rpy: [0.1, 0.2, 0.3]}}
task_space: position
bodies:
  - {link: link1, mass: 1.2, com: [0.15, 0.01, 0], inertia: {xx: 0.002, yy: 0.01, zz: 0.011, xy: 0.0003}}
  - {link: link2, mass: 0.8, com: [0.12, 0, 0.02], inertia: {xx: 0.001, yy: 0.006, zz: 0.0065, xz: -0.0002}}
  - {link: link3, mass: 0.3, com: [0.05, 0, 0]}
gravity: [0.5, -1, -g]
friction:
  j1: {viscous: 0.1, coulomb: 0.3, smoothing_velocity: v_s}
  j2: {viscous: 0.05, coulomb: 0.1}
  j3: {coulomb: 0.2, smoothing_velocity: v_s}
"""

#: A SCARA arm (classic DH) whose last two links are point masses on the last axis: its mass matrix is singular
#: everywhere (refused by check and derive), its IK has closed forms.
SCARA = """name: scara
parameters:
  g: {value: 9.81, unit: m/s^2}
serial:
  dh:
    convention: classic
    rows:
      - [q1, R, 0, 0.4, 0.3, 0, [-2.5, 2.5]]
      - [q2, R, 0, 0, 0.25, pi, [-2.5, 2.5]]
      - [q3, P, 0, 0, 0, 0, [0, 0.2]]
      - [q4, R, 0, 0, 0, 0]
task_space: [x, y, z, wz]
bodies:
  - {link: link1, mass: 5, com: [-0.15, 0, 0], inertia: {xx: 0.01, yy: 0.04, zz: 0.04}}
  - {link: link2, mass: 3, com: [-0.12, 0, 0], inertia: {xx: 0.01, yy: 0.02, zz: 0.02}}
  - {link: link3, mass: 1}
  - {link: link4, mass: 0.5}
gravity: [0, 0, -g]
scene:
  outputs: [fk, jacobian, mass_matrix, forward_dynamics]
"""

#: Every branch of symkin.dynamics.newton_euler at once.
ODD_ARM = """
name: odd_arm
parameters:
  l1: 0.3
  g: 9.81
serial:
  base: {xyz: [0.1, -0.2, 0.5], rpy: [0.3, -0.2, 0.7]}
  chain:
    - {name: j1, axis: [0, 0, 1], offset: 0.4}
    - {name: j2, type: P, axis: [0, 0.6, 0.8], origin: {xyz: [l1, 0, 0.05], rpy: [0.2, 0.1, -0.3]}, offset: 0.1}
    - {name: j3, axis: [1, 2, 2], origin: {xyz: [0.2, 0.1, 0], rpy: [-0.4, 0.3, 0.2]}}
    - {name: j4, axis: [0, -1, 0], origin: {xyz: [0.15, 0, 0.1], rpy: [1.1, 0, 0]}}
  tcp: {xyz: [0, 0, 0.1]}
task_space: position
bodies:
  - {link: link1, mass: 1.2, com: [0.15, 0.01, 0], inertia: {xx: 0.002, yy: 0.01, zz: 0.011, xy: 0.0003}}
  - {link: link1, mass: 0.4, com: [0.05, -0.02, 0.03]}
  - {link: link2, mass: 0, inertia: {xx: 0.001, yy: 0.002, zz: 0.0025, yz: 0.0001}}
  - {link: link4, mass: 0.3, com: [0.05, 0.01, 0], origin: {xyz: [0.01, 0, 0], rpy: [0, 0.5, 0]},
     inertia: {xx: 0.0004, yy: 0.0005, zz: 0.0003}}
gravity: [1.5, -2, -g]
friction:
  j3: {viscous: 0.1, coulomb: 0.3}
"""

#: The stock robot files of the example-robot-data package (its URDFs and meshes).
ROBOTS_DIR = Path(distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))


#: A torso carrying two arms and a head (a tree with a prismatic joint, friction and a drive): tests/model/test_trees.py,
#: tests/derivation/test_dynamics_derivatives.py.
TORSO = """
name: torso
parameters:
  g: 9.81
serial:
  base: {xyz: [0, 0, 0.8]}
  chain:
    - {name: waist, axis: [0, 0, 1], link: chest}
    - {name: l_shoulder, parent: chest, origin: {xyz: [0, 0.2, 0.3], rpy: [-0.3, 0, 0]}, axis: [0, 1, 0],
       link: l_upper}
    - {name: l_elbow, axis: [0, 1, 0], origin: {xyz: [0.3, 0, 0]}, link: l_fore}
    - {name: l_slide, type: P, axis: [1, 0, 0], limits: [0, 0.1], origin: {xyz: [0.25, 0, 0], rpy: [0.2, 0.1, 0]}, link: l_hand}
    - {name: r_shoulder, parent: chest, origin: {xyz: [0, -0.2, 0.3], rpy: [0.3, 0, 0]}, axis: [0, 1, 0],
       link: r_upper}
    - {name: r_elbow, axis: [0.3, 1, 0], origin: {xyz: [0.3, 0, 0.02]}, link: r_fore}
    - {name: head, parent: chest, origin: {xyz: [0, 0, 0.45]}, axis: [0, 0, 1], link: head}
  tip: l_hand
  tcp: {xyz: [0.05, 0, 0]}
task_space: pose
bodies:
  - {link: chest, mass: 8, com: [0, 0, 0.2], inertia: {xx: 0.2, yy: 0.18, zz: 0.1}}
  - {link: l_upper, mass: 1.5, com: [0.15, 0.01, 0], inertia: {xx: 0.002, yy: 0.012, zz: 0.012, xy: 0.0004}}
  - {link: l_fore, mass: 1.1, com: [0.12, 0, 0.01], inertia: {xx: 0.0015, yy: 0.008, zz: 0.008}}
  - {link: l_hand, mass: 0.4, com: [0.03, 0, 0]}
  - {link: r_upper, mass: 1.5, com: [0.15, -0.01, 0], inertia: {xx: 0.002, yy: 0.012, zz: 0.012}}
  - {link: r_fore, mass: 1.3, com: [0.13, 0, -0.01], inertia: {xx: 0.0016, yy: 0.009, zz: 0.009, yz: 0.0002}}
  - {link: head, mass: 2.0, com: [0.02, 0, 0.1], inertia: {xx: 0.01, yy: 0.01, zz: 0.008}}
gravity: [0, 0, -g]
friction:
  r_elbow: {viscous: 0.2, coulomb: 0.1}
actuators:
  waist: {rotor_inertia: 1e-4, gear_ratio: 100}
"""

"""The dual SCARA of docs/model-format.md with its link bodies, bar and rotors as an independent reference (kept out
of the product): every mass property written again from the document, the two legs as a Pinocchio kinematic tree
closed by a weld (tests/parallel/test_closure_dynamics.py, tests/parallel/test_rubbing_legs.py), and assembled states
near its home pose."""

from __future__ import annotations

import numpy as np

from symkin.runtime.parallel import solve_closure

D, L1, L2, E = 0.3, 0.25, 0.25, 0.1
HOME = np.array([0.0, 0.3, 0.1, 0.0])
GRAVITY = 9.81
ROTOR = 10**2 * 1e-5
#: (joint, parent, R or P, origin, mass, com, principal inertia) as the document declares them.
TREE = [("theta1", None, "R", [-D / 2, 0, 0], 0.3, [0.12, 0, 0], [0.0001, 0.0015, 0.0016]),
        ("elbow1", "theta1", "R", [L1, 0, 0], 0.25, [0.1, 0.01, 0], [0.0002, 0.0011, 0.0012]),
        ("lift1", "elbow1", "P", [L2, 0, 0], 0.1, [0, 0, 0.05], [0.0001, 0.0001, 0.00002]),
        ("wrist1", "lift1", "R", [0, 0, 0], 0.0, [0, 0, 0], [0, 0, 0]),
        ("phi2", None, "R", [D / 2, 0, 0], 0.3, [0.12, 0, 0], [0.0001, 0.0015, 0.0016]),
        ("knee2", "phi2", "R", [L1, 0, 0], 0.25, [0.1, 0, 0.01], [0.0002, 0.0011, 0.0012]),
        ("slide2", "knee2", "P", [L2, 0, 0], 0.1, [0, 0, 0.05], [0.0001, 0.0001, 0.00002]),
        ("hand2", "slide2", "R", [0, 0, 0], 0.05, [0.01, 0, 0.02], [0.00002, 0.00002, 0.00003])]
#: The bar on leg 1's wrist, whose frame is the bar's attachment (-e, 0, 0): the bar's frame is e along x.
BAR = (0.2, [0, 0.01, 0], [0.0001, 0.0003, 0.0004])
ACTIVE = ("theta1", "lift1", "phi2", "knee2")
#: The closure's rows that are not identically zero (each leg's x, y, z and yaw; all axes are vertical).
CLOSURE_ROWS = [0, 1, 2, 5, 6, 7, 8, 11]
PASSIVE = ("elbow1", "wrist1", "slide2", "hand2")


def pinocchio_tree(pin):
    """The two legs as a Pinocchio tree, the bar on leg 1's wrist, and the weld of leg 2's hand to the bar."""
    tree = pin.Model()
    ids = {}
    for name, parent, kind, origin, mass, com, inertia in TREE:
        joint = pin.JointModelRZ() if kind == "R" else pin.JointModelPZ()
        ids[name] = tree.addJoint(ids.get(parent, 0), joint, pin.SE3(np.eye(3), np.array(origin, float)), name)
        if mass:
            tree.appendBodyToJoint(ids[name], pin.Inertia(mass, np.array(com, float), np.diag(inertia)),
                                   pin.SE3.Identity())
    mass, com, inertia = BAR
    tree.appendBodyToJoint(ids["wrist1"], pin.Inertia(mass, np.array(com, float), np.diag(inertia)),
                           pin.SE3(np.eye(3), np.array([E, 0, 0])))
    tree.gravity = pin.Motion(np.array([0, 0, -GRAVITY]), np.zeros(3))
    order = [name for name, *_ in TREE]
    tree.armature = np.array([ROTOR if name in ACTIVE else 0.0 for name in order])
    weld = pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, tree, ids["hand2"], pin.SE3.Identity(),
                                    ids["wrist1"], pin.SE3(np.eye(3), np.array([2 * E, 0, 0])),
                                    pin.ReferenceFrame.LOCAL)
    constraints = pin.StdVec_RigidConstraintModel()
    constraints.append(weld)
    return tree, constraints, order


def assembled_states(scara, count, rng):
    """Assembled (q, s, p) near the home pose in the home assembly mode, by the closure's Gauss-Newton."""
    ik = solve_closure(scara, [1.0, 0.1, 1.6, 0.0], np.zeros(4), HOME, unknowns=("q", "s"), max_step=0.2)
    q0, s0 = ik.solution["q"], ik.solution["s"]
    states = []
    while len(states) < count:
        q = q0 + rng.uniform(-0.03, 0.03, 4) * [1, 1, 1, 1]
        fk = solve_closure(scara, q, s0, HOME, unknowns=("p", "s"))
        if fk.all_converged:
            states.append((q, fk.solution["s"], fk.solution["p"]))
    return states


def constraint_accelerations(pin):
    """(q, s, zd, efforts) -> the actuated joints' accelerations by Pinocchio's ``constraintDynamics`` of
    :func:`pinocchio_tree` (proximal, mu = 1e-6 on the weld's two rows that all-vertical axes make redundant) at the
    assembled (q, s) moving with the mechanism's velocities zd (actuated, then passive joints first) under the
    actuators' efforts."""
    from benchmarks.competitors import constraint_dynamics_of

    tree, constraints, order = pinocchio_tree(pin)
    data, datas, _ = constraint_dynamics_of(pin, tree, constraints)
    settings = pin.ProximalSettings(1e-14, 1e-6, 100)
    active = [order.index(name) for name in ACTIVE]
    passive = [order.index(name) for name in PASSIVE]

    def accelerations(q, s, zd, efforts):
        x, v, tau = np.zeros(len(order)), np.zeros(len(order)), np.zeros(len(order))
        x[active], x[passive], v[active], v[passive], tau[active] = q, s, zd[:4], zd[4:8], efforts
        return pin.constraintDynamics(tree, data, x, v, tau, constraints, datas, settings)[active]

    return accelerations

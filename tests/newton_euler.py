"""An independent numeric recursive Newton-Euler inverse dynamics (seed sec. 4.4, "Iterative Approach").

Written for the tests only, from the textbook algorithm (Craig, *Introduction to Robotics*,
sec. 6.5), on a classic DH table of plain floats: it shares no code with symkin.
Everything is expressed in the base frame:

1. outward: angular velocity and acceleration of each link, linear acceleration of its
   centre of mass (gravity enters as an upward acceleration of the base);
2. Newton-Euler per link: F = m a_c, N = I alpha + w x I w;
3. inward: forces and moments back to the base; tau_i = n_i . z_{i-1}.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Link:
    """Row i of a classic DH table (^{i-1}T_i = Rz(theta) Tz(d) Tx(a) Rx(alpha)) and link i's mass properties.

    com and inertia (about the CoM) are given in frame i.
    """

    d: float
    a: float
    alpha: float
    mass: float
    com: tuple[float, float, float]
    inertia: np.ndarray


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct],
                     [st, ct * ca, -ct * sa, a * st],
                     [0, sa, ca, d],
                     [0, 0, 0, 1.0]])


def inverse_dynamics(links: list[Link], gravity: np.ndarray, q, qd, qdd) -> np.ndarray:
    """Joint torques of revolute joints for the motion (q, qd, qdd)."""
    n = len(links)
    T = np.eye(4)
    z_prev, o_prev = T[:3, 2].copy(), T[:3, 3].copy()
    w = np.zeros(3)
    dw = np.zeros(3)
    a_origin = -np.asarray(gravity, dtype=float)  # acceleration of the point o_{i-1}
    axes, origins, forces, moments, coms, ends = [], [], [], [], [], []
    for i, link in enumerate(links):
        z, o = z_prev, o_prev
        dw = dw + z * qdd[i] + np.cross(w, z * qd[i])
        w = w + z * qd[i]
        T = T @ dh_transform(q[i], link.d, link.a, link.alpha)
        R, end = T[:3, :3], T[:3, 3].copy()
        c = end + R @ np.asarray(link.com)
        a_c = a_origin + np.cross(dw, c - o) + np.cross(w, np.cross(w, c - o))
        I = R @ link.inertia @ R.T
        forces.append(link.mass * a_c)
        moments.append(I @ dw + np.cross(w, I @ w))
        axes.append(z)
        origins.append(o)
        coms.append(c)
        ends.append(end)
        a_origin = a_origin + np.cross(dw, end - o) + np.cross(w, np.cross(w, end - o))
        z_prev, o_prev = R[:, 2].copy(), end
    tau = np.zeros(n)
    f_next = np.zeros(3)
    n_next = np.zeros(3)  # moment about the origin of frame i (= o_i)
    for i in reversed(range(n)):
        o = origins[i]
        f = f_next + forces[i]
        m = n_next + moments[i] + np.cross(coms[i] - o, forces[i]) + np.cross(ends[i] - o, f_next)
        tau[i] = m @ axes[i]
        f_next, n_next = f, m
    return tau


def links_of(rows) -> list[Link]:
    """The links of rows with d, a, alpha, mass, com and inertia (xx, yy, zz, xy, xz, yz), such as the
    generated chains of benchmarks/chain_models.py (plain data: no symkin code)."""
    links = []
    for row in rows:
        xx, yy, zz, xy, xz, yz = row.inertia
        inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        links.append(Link(row.d, row.a, row.alpha, row.mass, row.com, inertia))
    return links

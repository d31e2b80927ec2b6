"""Generated n-joint serial chains: inputs nobody wrote by hand, for the scaling benchmark and tests.

``dh_chain(n)`` is a classic-DH arm of n revolute joints whose twists cycle through
+90 deg, -90 deg and a generic 0.3 rad (no special structure for the derivation to exploit),
with link offsets and lengths that change along the chain and a rigid body (mass, off-axis
centre of mass, full inertia tensor with products of inertia) on every link.  The numbers
are plain floats, so an independent numeric reference can use the same table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

TWISTS = (("deg(90)", math.pi / 2), ("deg(-90)", -math.pi / 2), ("0.3", 0.3))


@dataclass(frozen=True)
class ChainLink:
    """Row of the classic DH table and the body of its link (CoM and inertia about it in frame i)."""

    d: float
    a: float
    alpha: float
    alpha_text: str
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]  # xx, yy, zz, xy, xz, yz


def dh_chain(n: int) -> list[ChainLink]:
    """The n links of the generated chain."""
    links = []
    for i in range(n):
        text, alpha = TWISTS[i % len(TWISTS)]
        links.append(ChainLink(d=0.1 if i % 2 == 0 else 0.0, a=0.2 + 0.01 * i, alpha=alpha, alpha_text=text,
                               mass=1.0 + 0.1 * i, com=(-0.1, 0.01, 0.02),
                               inertia=(0.01, 0.012, 0.008, 0.001, 0.0, 0.0005)))
    return links


def chain_yaml(n: int) -> str:
    """The model file of ``dh_chain(n)``: pose task space, gravity along -z."""
    lines = [f"name: chain{n}", f"description: generated {n}-joint classic-DH chain (benchmarks/chain_models.py)",
             "parameters:", "  g: {value: 9.81, unit: m/s^2}", "serial:", "  dh:", "    convention: classic",
             "    rows:"]
    links = dh_chain(n)
    lines += [f"      - [q{i + 1}, R, 0, {link.d!r}, {link.a!r}, {link.alpha_text}]" for i, link in enumerate(links)]
    lines += ["task_space: pose", "gravity: [0, 0, -g]", "bodies:"]
    for i, link in enumerate(links):
        xx, yy, zz, xy, xz, yz = link.inertia
        lines.append(f"  - {{link: link{i + 1}, mass: {link.mass!r}, com: {list(link.com)}, "
                     f"inertia: {{xx: {xx}, yy: {yy}, zz: {zz}, xy: {xy}, xz: {xz}, yz: {yz}}}}}")
    return "\n".join(lines) + "\n"


def odd_frames_urdf(n: int, seed: int = 0, depth: int = 3) -> str:
    """A URDF of n revolute joints as robot files ship them (TIAGo, iCub): every ``<origin>`` and inertial
    frame with arbitrary rpy written to 5 decimals (angles such as -2.06791, no multiple of pi/2); between
    two joints a fixed adapter link, and on each chain link a fixed chain of ``depth`` cover links (all
    lumped into the chain link through their composed frames); a fixed tool frame; physical masses and
    principal moments.  Joints q1..qn, tip ``tool``."""
    import numpy as np

    rng = np.random.default_rng(seed)

    def origin() -> str:
        return (f'<origin xyz="{" ".join(f"{v:.4f}" for v in rng.uniform(-0.2, 0.2, 3))}" '
                f'rpy="{" ".join(f"{v:.5f}" for v in rng.uniform(-math.pi, math.pi, 3))}"/>')

    def link(name: str) -> str:
        mass, (a, b, c) = rng.uniform(0.5, 2.0), rng.uniform(0.001, 0.01, 3)
        return (f'  <link name="{name}"><inertial><mass value="{mass:.4f}"/>{origin()}'
                f'<inertia ixx="{a + b:.5f}" iyy="{b + c:.5f}" izz="{a + c:.5f}" ixy="0" ixz="0" iyz="0"/>'
                "</inertial></link>")

    def fixed(parent: str, child: str) -> str:
        return (f'  <joint name="{child}_fixed" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
                f"{origin()}</joint>")

    lines = ['<?xml version="1.0"?>', f'<robot name="odd_frames{n}">', '  <link name="base"/>']
    parent = "base"
    for k in range(1, n + 1):
        lines += [link(f"adapter{k}"), fixed(parent, f"adapter{k}"), link(f"link{k}"),
                  f'  <joint name="q{k}" type="revolute"><parent link="adapter{k}"/><child link="link{k}"/>'
                  f'{origin()}<axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" effort="10" velocity="2"/></joint>']
        holder = f"link{k}"
        for d in range(1, depth + 1):
            lines += [link(f"cover{k}_{d}"), fixed(holder, f"cover{k}_{d}")]
            holder = f"cover{k}_{d}"
        parent = f"link{k}"
    lines += ['  <link name="tool"/>', fixed(parent, "tool"), "</robot>"]
    return "\n".join(lines) + "\n"

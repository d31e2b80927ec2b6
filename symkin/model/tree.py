"""The joints of a serial model as a tree (issue 30): which joint carries which, and where the TCP hangs.

A serial chain is the tree with one leaf; a joint with ``parent: LINK`` starts a branch at the link of
an earlier joint (``base`` for the base), so one model holds a torso with two arms, a hand's fingers or
a device's counterweight branch. Joints are listed parents first. Kinematics and dynamics ask this
module for each joint's parent and for the joints between the base and a link.
"""

from __future__ import annotations

from collections.abc import Sequence

from symkin.model.schema import Joint, Model

#: The name of the base in ``parent:``.
BASE = "base"


def parent_indices(model: Model) -> tuple[int, ...]:
    """The index of each joint's parent joint (-1 for the base): the previous joint unless ``parent`` says."""
    return parent_indices_of(model.joints)


def parent_indices_of(joints: Sequence[Joint]) -> tuple[int, ...]:
    """:func:`parent_indices` of a sequence of joints."""
    index = {joint.link: k for k, joint in enumerate(joints)}
    return tuple(k - 1 if joint.parent is None else -1 if joint.parent == BASE else index[joint.parent]
                 for k, joint in enumerate(joints))


def path_to(parents: tuple[int, ...], k: int) -> tuple[int, ...]:
    """The joints from the base to joint ``k`` included, base first."""
    path = []
    while k >= 0:
        path.append(k)
        k = parents[k]
    return tuple(reversed(path))


def tip_index(model: Model) -> int:
    """The joint whose link carries the TCP: ``serial.tip`` or the last joint."""
    if model.tip is None:
        return len(model.joints) - 1
    return next(k for k, joint in enumerate(model.joints) if joint.link == model.tip)


def is_chain(model: Model) -> bool:
    """True if every joint carries the next one (no branch) and the TCP is on the last link."""
    return all(p == k - 1 for k, p in enumerate(parent_indices(model))) and tip_index(model) == len(model.joints) - 1

"""The ``wrist:`` section: a serial chain carried by a parallel platform (a hybrid device).

The section has the serial format (``dh:`` or ``chain:``, ``base:``, ``tcp:``, ``tip:``) and the
serial model's ``bodies:``, ``actuators:`` and ``friction:`` for the wrist's own links and joints; the
chain starts in the platform frame (docs/model-format.md, "Hybrid devices").
"""

from __future__ import annotations

from typing import Any

from symkin.errors import name_list
from symkin.model import coordinates
from symkin.model.body_build import read_actuators, read_bodies, read_friction, with_motor_effort_limits
from symkin.model.reader import Reader
from symkin.model.rotors import with_rotors
from symkin.model.schema import PLATFORM_COORDINATES, Friction, Parallel, Wrist
from symkin.model.serial_build import read_serial, read_tip
from symkin.model.yaml_source import KeyPath

#: Keys of ``wrist:`` that a serial section has too.
SERIAL_KEYS = ("dh", "chain", "base", "tcp", "tip")
WRIST_KEYS = SERIAL_KEYS + ("bodies", "actuators", "friction")
#: The link of the platform in the device's chain (:mod:`symkin.parallel.hybrid`); each platform
#: coordinate c moves a link ``platform_<c>`` before it.
PLATFORM_LINK = "platform"


def platform_link_names() -> tuple[str, ...]:
    """The link names the device's chain gives the platform's motion (taken for the wrist's links)."""
    return (PLATFORM_LINK,) + tuple(f"{PLATFORM_LINK}_{c}" for c in PLATFORM_COORDINATES)


def read_wrist(r: Reader, section: Any, parallel: Parallel) -> tuple[Wrist | None, tuple[Friction, ...]]:
    """The wrist a parallel platform carries and the friction of its joints (problems go to ``r``)."""
    path: KeyPath = ("wrist",)
    section = r.mapping(path, section, optional=WRIST_KEYS)
    if section is None:
        return None, ()
    serial = {key: value for key, value in section.items() if key in SERIAL_KEYS}
    joints, base, tcp = read_serial(r, serial, path)
    tip = read_tip(r, serial, joints, path)
    names = tuple(j.name for j in joints)
    bodies = read_bodies(r, section.get("bodies", []), tuple(j.link for j in joints), path + ("bodies",))
    actuators = read_actuators(r, section.get("actuators", {}), names, path + ("actuators",))
    friction = read_friction(r, section.get("friction", {}), names, path + ("friction",))
    joints = with_motor_effort_limits(joints, actuators)
    joints, bodies = with_rotors(r, joints, actuators, bodies, path + ("actuators",))
    _check_names(r, path + (("chain",) if "chain" in section else ("dh", "rows")), joints, parallel)
    return Wrist(joints, base, tcp, tip, bodies, actuators), friction


def _check_names(r: Reader, path: KeyPath, joints: tuple, parallel: Parallel) -> None:
    """The wrist's joints and links (declared at ``path``) may not take the names of the platform's coordinates,
    the legs' variables or the links the device's chain gives the platform."""
    taken = {name: f"the platform coordinate '{name}'" for name in PLATFORM_COORDINATES}
    for leg in parallel.legs:
        for joint in leg.joints:
            for k, variable in enumerate(joint.variables):
                for symbol in coordinates.all_symbol_names(variable) if k == joint.active else (variable,):
                    taken[symbol] = f"the variable '{variable}' of joint '{joint.name}' ({leg.name})"
    links = set(platform_link_names())
    for joint in joints:
        clash = next((taken[s] for s in coordinates.all_symbol_names(joint.name) if s in taken), None)
        if clash is not None:
            r.fail(path, f"the wrist joint '{joint.name}' clashes with {clash}",
                   "give the wrist's joints names of their own (psi1, psi2, ...)")
        if joint.link in links:
            r.fail(path, f"the wrist link '{joint.link}' is a name the platform's motion takes",
                   f"rename the link; taken: {name_list(sorted(links))}")

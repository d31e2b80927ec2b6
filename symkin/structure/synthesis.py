"""Topology synthesis of symmetric parallel mechanisms (seed sec. 2.2.2, Tables 8.1 and 8.2).

The seed's example: a haptic interface for spatial interaction in (x, y, z) needs F = 3;
fully parallel (eq. 8.1, P_g = 1) gives k = 3 legs; eq. (8.4) gives sum f_i = 15 joint DoF,
five per leg for equal behaviour in all directions.  Every ordered chain of R, P, U, C and S
joints (base to platform) with five DoF is a candidate (Table 8.1); the candidates are then
reduced by the criteria of the text, in its order (Table 8.2):

1. Functionality as a TPM (Carricato [2, 3]):
   a. no spherical joint (Carricato's first rule);
   b. a T5 leg comprises four or five rotatory DoF: at most one translational DoF
      (a P joint or the slide of a C joint);
   c. no equivalent spherical joint: a C joint inside the leg (not at the base or the
      platform) next to a U joint is a telescopic strut whose axis runs through the U
      joint's centre, so the C rotation and the U rotate about three concurrent axes;
2. Position of actuators: rotary, linear and piston actuators are R, P and C joints, fixed
   to the frame when they are the base joint.  A U (or S) joint at the base puts the
   actuators inside the chain, except a linear actuator directly after it: a strut pivoting
   at the base (as the hydraulic legs of a Stewart-Gough platform);
3. Number of joints: two adjacent one-DoF joints concentrate into one joint (R-R into a U,
   R-P or P-R into a C), which simplifies the geometry and the kinematic equations.

The seed gives the criteria and the outcome (UPU, PUU, CUR, CRU, RUU and RUC) but its
Tables 8.1 and 8.2 are missing; this is a reconstruction from the text.  Rules 1a, 1b, 2
and 3 are the text's; 1c and the strut exception of rule 2 are the interpretations needed
to reproduce the stated outcome (UPU survives although its base joint is a U; RCU and UCR
do not although R and C joints can carry actuators), and are labelled as such.

Rule 1 applies to translational mechanisms only.  For a six-DoF platform a leg must not
constrain it (at least three rotatory and at most three translational DoF, so that its six
DoF are independent); other motions use rules 2 and 3 alone.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from symkin.structure.mobility import SPATIAL, joint_dof_budget

JOINT_DOF = {"R": 1, "P": 1, "U": 2, "C": 2, "S": 3}
ROTATIONAL_DOF = {"R": 1, "P": 0, "U": 2, "C": 1, "S": 3}
#: Joints an actuator can be: rotary (R), linear (P), piston (C) (seed sec. 2.2.2).
ACTUABLE = frozenset("RPC")
#: Order of the joint letters in listings.
JOINT_ORDER = "RPUCS"


@dataclass(frozen=True)
class Criterion:
    """An elimination criterion of seed sec. 2.2.2.

    Attributes:
        key: short identifier.
        group: the criterion of the text it belongs to.
        rule: what it demands.
        source: ``seed`` when the text states it, ``reconstruction`` when it is the
            interpretation needed to reproduce the text's outcome.
    """

    key: str
    group: str
    rule: str
    source: str


TPM = "functionality as a TPM (Carricato)"
ACTUATORS = "position of actuators"
JOINTS = "number of joints"

CRITERIA = (
    Criterion("spherical", TPM, "no S joint (Carricato's first rule)", "seed"),
    Criterion("rotations", TPM, "four or five rotatory DoF per leg (T5 chain): at most one translational DoF", "seed"),
    Criterion("strut", TPM, "no C joint inside the leg next to a U joint (a telescopic strut through the U centre "
                            "makes an equivalent S joint)", "reconstruction"),
    Criterion("six_dof", "mobility of the leg", "a leg of a six-DoF platform has at least three rotatory and at most "
                                                "three translational DoF", "construction"),
    Criterion("actuator", ACTUATORS, "an actuated R, P or C joint at the base (fixed to the frame); a U or S at the "
                                     "base only with a linear actuator (P) directly after it", "seed + reconstruction"),
    Criterion("concentration", JOINTS, "no two adjacent one-DoF joints that concentrate into one joint (R-R: U; "
                                       "R-P, P-R: C)", "seed"),
)
CRITERION = {c.key: c for c in CRITERIA}


@dataclass(frozen=True)
class Verdict:
    """One candidate leg topology and the first criterion that removes it (None: it survives)."""

    topology: str
    eliminated_by: Criterion | None
    detail: str = ""

    @property
    def criterion(self) -> Criterion:
        """The criterion that eliminated the topology (a survivor has none: ValueError)."""
        if self.eliminated_by is None:
            raise ValueError(f"{self.topology} survives: no criterion eliminated it")
        return self.eliminated_by

    @property
    def distribution(self) -> str:
        """How the leg's DoF are distributed over its joints, e.g. ``2+2+1`` (Table 8.2's grouping)."""
        return "+".join(str(d) for d in sorted((JOINT_DOF[j] for j in self.topology), reverse=True))


@dataclass(frozen=True)
class Synthesis:
    """The candidates and survivors of a synthesis.

    Attributes:
        dof: F.
        legs: k.
        leg_dof: DoF of each leg (sum f_i / k).
        translational: whether the TPM criteria were applied.
        verdicts: every candidate (Table 8.1) with its verdict (Table 8.2), in enumeration order.
    """

    dof: int
    legs: int
    leg_dof: int
    translational: bool
    verdicts: tuple[Verdict, ...]

    @property
    def budget(self) -> int:
        return joint_dof_budget(self.dof, self.legs)

    @property
    def survivors(self) -> tuple[str, ...]:
        return tuple(v.topology for v in self.verdicts if v.eliminated_by is None)

    @property
    def eliminated(self) -> tuple[Verdict, ...]:
        return tuple(v for v in self.verdicts if v.eliminated_by is not None)


def leg_topologies(leg_dof: int, joints: str = JOINT_ORDER) -> Iterator[str]:
    """Every ordered chain of the given joint letters whose DoF sum to ``leg_dof`` (Table 8.1)."""
    if leg_dof == 0:
        yield ""
        return
    for joint in joints:
        if JOINT_DOF[joint] <= leg_dof:
            for rest in leg_topologies(leg_dof - JOINT_DOF[joint], joints):
                yield joint + rest


def _tpm(topology: str) -> tuple[str, str] | None:
    if "S" in topology:
        return "spherical", "has an S joint"
    rotational = sum(ROTATIONAL_DOF[j] for j in topology)
    if rotational < 4:
        return "rotations", f"{rotational} rotatory and {sum(JOINT_DOF[j] for j in topology) - rotational} " \
                            "translational DoF"
    for i in range(1, len(topology) - 1):
        if topology[i] == "C" and "U" in (topology[i - 1], topology[i + 1]):
            return "strut", f"C joint {i + 1} next to a U joint inside the leg"
    return None


def _six_dof(topology: str) -> tuple[str, str] | None:
    rotational = sum(ROTATIONAL_DOF[j] for j in topology)
    translational = sum(JOINT_DOF[j] for j in topology) - rotational
    if rotational < 3 or translational > 3:
        return "six_dof", f"{rotational} rotatory and {translational} translational DoF"
    return None


def _actuator(topology: str) -> tuple[str, str] | None:
    base = topology[0]
    if base in ACTUABLE:
        return None
    if base in "US" and len(topology) > 1 and topology[1] == "P":
        return None
    return "actuator", f"{base} joint at the base, the actuators sit inside the chain"


def _concentration(topology: str) -> tuple[str, str] | None:
    for a, b in zip(topology, topology[1:]):
        if (a, b) == ("R", "R"):
            return "concentration", "R-R concentrates into a U joint"
        if {a, b} == {"R", "P"}:
            return "concentration", f"{a}-{b} concentrates into a C joint"
    return None


def judge(topology: str, translational: bool, dof: int = 3) -> Verdict:
    """The first criterion (in the text's order) that removes ``topology``, if any."""
    checks = ([_tpm] if translational else [_six_dof] if dof == SPATIAL else []) + [_actuator, _concentration]
    for check in checks:
        found = check(topology)
        if found is not None:
            key, detail = found
            return Verdict(topology, CRITERION[key], detail)
    return Verdict(topology, None)


def synthesize(dof: int = 3, legs: int = 3, translational: bool | None = None, joints: str = JOINT_ORDER) -> Synthesis:
    """Enumerate and reduce the symmetric k-leg topologies of an F-DoF spatial mechanism.

    Args:
        dof: F, the mechanism's DoF.
        legs: k, the number of legs (P_g = k / F, eq. 8.1).
        translational: apply the TPM criteria (default: when F = 3, the seed's case).
        joints: joint letters to build legs from.

    Raises:
        ValueError: the joint-DoF budget (eq. 8.4) does not split evenly over the legs, or
            the TPM criteria are asked for legs that are not five-DoF (T5) chains.
    """
    budget = joint_dof_budget(dof, legs)
    if dof < 1 or legs < 1 or dof > SPATIAL:
        raise ValueError("the DoF must be between 1 and 6 and there must be at least one leg")
    if budget % legs:
        raise ValueError(f"the {budget} joint DoF of eq. (8.4) (F + 6(k - 1) with F = {dof}, k = {legs}) do not split "
                         f"evenly over {legs} legs; choose another number of legs")
    unknown = set(joints) - set(JOINT_DOF)
    if unknown or not joints:
        raise ValueError(f"unknown joint letters {sorted(unknown)}; use a selection of {JOINT_ORDER}")
    leg_dof = budget // legs
    translational = dof == 3 if translational is None else translational
    if translational and leg_dof != 5:
        raise ValueError(f"the TPM criteria (Carricato's T5 chains) are stated for five-DoF legs, these have {leg_dof}")
    ordered = "".join(j for j in JOINT_ORDER if j in joints)
    verdicts = tuple(judge(t, translational, dof) for t in leg_topologies(leg_dof, ordered))
    return Synthesis(dof, legs, leg_dof, translational, verdicts)

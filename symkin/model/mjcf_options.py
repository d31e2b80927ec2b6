"""What an MJCF file's ``<option>`` and bodies ask of the simulation beyond the rigid tree, and what symkin makes of
it (:mod:`symkin.model.mjcf_source`): disable flags that change the model are honoured (the model has none of
those terms) or noted, and the forces symkin does not model (a medium's fluid forces, bodies' gravity
compensation) are named in the model's notes."""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.model.yaml_source import Document


def disabled(model: Any, flag: str) -> bool:
    """Whether ``<option><flag NAME="disable"/>`` switched off MuJoCo's ``mjDSBL_<flag>`` in the compiled model."""
    import mujoco

    return bool(int(model.opt.disableflags) & int(getattr(mujoco.mjtDisableBit, f"mjDSBL_{flag}")))


#: Disable flags that change what the model is and how symkin takes them (the others - contact, warm start,
#: sensors, ... - concern simulation only).
HONOURED_FLAGS = {"GRAVITY": "no gravity", "DAMPER": "no joint damping", "FRICTIONLOSS": "no joint frictionloss",
                  "SPRING": "no joint springs", "CONSTRAINT": "no equality couplings",
                  "EQUALITY": "no equality couplings"}
#: ... and those symkin cannot follow, noted: its model keeps the joint ranges and the actuators' effort limits.
NOTED_FLAGS = {"LIMIT": "MuJoCo does not enforce the joint ranges (symkin keeps them as the joints' limits)",
               "ACTUATION": "MuJoCo applies no actuator forces (symkin keeps the actuators' effort limits)"}


def option_notes(document: Document, model: Any) -> None:
    """A note for each disable flag of ``<option>`` that changes the model: what symkin made of it."""
    notes = [f"MJCF <option><flag {flag.lower()}=\"disable\"/>: {meaning}" for flag, meaning in HONOURED_FLAGS.items()
             if disabled(model, flag)]
    notes += [f"MJCF <option><flag {flag.lower()}=\"disable\"/>: {meaning}" for flag, meaning in NOTED_FLAGS.items()
              if disabled(model, flag)]
    medium = {name: value for name, value in (("density", float(model.opt.density)),
                                              ("viscosity", float(model.opt.viscosity)),
                                              ("wind", float(np.max(np.abs(model.opt.wind))))) if value}
    if medium:  # MuJoCo's qfrc_fluid: drag, lift and buoyancy of the bodies' geoms in the medium
        notes.append(f"MJCF <option> {', '.join(f'{k}={v!r}' for k, v in medium.items())}: MuJoCo applies fluid forces "
                     "to the bodies, which symkin does not model (they are not in V, G or tau)")
    import mujoco

    compensated = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}" for b in range(model.nbody)
                   if float(model.body_gravcomp[b])]
    if compensated:
        notes.append(f"bodies {', '.join(compensated)} have gravcomp: MuJoCo cancels that share of their weight by a "
                     "passive force, which symkin does not model (its G holds their whole weight)")
    if notes:
        document.data["notes"] = [*document.data.get("notes", []), *notes]

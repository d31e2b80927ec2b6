"""Sample models shared by test modules (issue 35: one place, not defined in one test module and imported by
another).  Each is read from where the documentation declares it, so the tests check the model a reader sees."""

from __future__ import annotations

import re

from conftest import ROOT

MODEL_FORMAT = ROOT / "docs" / "model-format.md"


def dual_scara_text() -> str:
    """The dual SCARA of docs/model-format.md ("Legs of any topology"): two SCARA legs R-R-P-R carrying a bar, a
    Schoenflies platform (x, y, z, yaw) whose legs have no distance form; its lifts declare no limits."""
    match = re.search(r"cat > dual_scara.yaml <<'EOF_MODEL'\n(.*?)^EOF_MODEL$", MODEL_FORMAT.read_text(), re.S | re.M)
    assert match, "docs/model-format.md lost the dual SCARA"
    return match.group(1)


def dual_scara_dynamics_text() -> str:
    """The dual SCARA with its link bodies, bar and rotors (docs/model-format.md, after "Legs of any topology"): the
    model above with the gravity and bodies the document appends to it."""
    match = re.search(r"<<'EOF_BODIES'\n(.*?)^EOF_BODIES$", MODEL_FORMAT.read_text(), re.S | re.M)
    assert match, "docs/model-format.md lost the dual SCARA's bodies"
    return dual_scara_text() + match.group(1)

"""Models that docs/model-format.md declares rather than models/ (plain text: no symkin code), for the benchmarks
that time them as the document writes them: its heredocs, in order (the dual SCARA's bodies appended to the model,
as the document's `cat dual_scara.yaml - > dual_scara_dynamics.yaml` does)."""

from __future__ import annotations

import re
from pathlib import Path

DOCUMENT = Path(__file__).resolve().parent.parent / "docs" / "model-format.md"
#: name -> the heredocs (their end markers) whose concatenation is the model file.
DOCUMENTED = {"dual_scara": ("EOF_MODEL", "EOF_BODIES")}


def model_text(name: str) -> str:
    """The model file ``name`` as docs/model-format.md writes it.

    Raises:
        ValueError: the document no longer holds one of its heredocs.
    """
    document = DOCUMENT.read_text()
    parts = []
    for end in DOCUMENTED[name]:
        found = re.search(rf"<<'{end}'\n(.*?)^{end}$", document, re.S | re.M)
        if found is None:
            raise ValueError(f"{DOCUMENT}: no heredoc {end} (the {name} model) any more")
        parts.append(found.group(1))
    return "".join(parts)

"""URDF text that symkin generated from another robot file (a xacro expansion, a compiled MJCF model), read
by the URDF reader with its messages, marks and notes moved back to the source file's lines."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from symkin.errors import ModelError, Problem
from symkin.model.urdf_source import urdf_document
from symkin.model.yaml_source import Document


@dataclass(frozen=True)
class GeneratedUrdf:
    """URDF text generated from a source file, and the source place of every line of it."""

    text: str
    #: lines[i]: (file, line, column) of the source element written on output line i + 1 (line and
    #: column None where the source gives none).
    lines: tuple[tuple[str, Any, Any], ...]

    def place(self, line: int | None) -> tuple[str, Any, Any] | None:
        """The source place of output line ``line``, or None outside the text."""
        return self.lines[line - 1] if line is not None and 1 <= line <= len(self.lines) else None


def read_generated_urdf(generated: GeneratedUrdf, file: str, **urdf: Any) -> Document:
    """The model document of ``generated`` (``urdf``: the URDF reader's tip, base, locks, snap_angles),
    its problems, marks and notes located in the source (``file``, or an included file)."""
    try:
        document = urdf_document(generated.text, file, **urdf)
    except ModelError as exc:
        raise located(exc, generated, file) from None
    for key, (line, *_) in list(document.marks.items()):
        place = generated.place(line)
        if place is not None:
            source, source_line, column = place
            document.marks[key] = (source_line, column) if source == file else (source_line, column, source)
    if "notes" in document.data:
        document.data["notes"] = [_NOTE_LINE.sub(lambda m: _note_place(generated, int(m.group(1)), file), note)
                                  for note in document.data["notes"]]
    return document


def located(error: ModelError, generated: GeneratedUrdf, file: str) -> ModelError:
    """``error`` of the URDF reader on the generated text, each problem moved to its source element."""
    problems = []
    for p in error.problems:
        place = generated.place(p.line) if p.file == file else None
        problems.append(p if place is None else Problem(place[0], place[1], place[2], p.key, p.message, p.fix))
    return ModelError(problems)


_NOTE_LINE = re.compile(r"^line (\d+): ")


def _note_place(generated: GeneratedUrdf, line: int, file: str) -> str:
    """``line N: `` of a URDF reader's note on the generated text, as the place in the source (none where the
    source gives no line)."""
    place = generated.place(line)
    if place is None or place[1] is None:
        return ""
    source, source_line, _ = place
    return f"line {source_line}: " if source == file else f"{source}, line {source_line}: "

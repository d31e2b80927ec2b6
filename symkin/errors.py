"""Exceptions raised by symkin.

Every problem with user input is a :class:`ModelError`: it carries one or more
:class:`Problem` records, each naming the file, the line and column, the key path inside
the document and a suggested fix, so that a command-line user can go straight to the
offending line.  The CLI turns a ``ModelError`` into exit code 2.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass


#: Names a message lists before it says how many more there are (a hostile file can have thousands of links).
LISTED_NAMES = 20


def name_list(names: Iterable[str], limit: int = LISTED_NAMES) -> str:
    """``names`` joined by commas, the first ``limit`` of them and "... and N more" beyond."""
    names = list(names)
    shown = ", ".join(str(name)[:80] for name in names[:limit])
    return shown + (f", ... and {len(names) - limit} more" if len(names) > limit else "")


class SymkinError(Exception):
    """Base class of every error symkin raises on purpose."""


@dataclass(frozen=True)
class Problem:
    """One problem found in a model file.

    Attributes:
        file: path of the model file as the user gave it.
        line: 1-based line number, or None when the problem concerns the whole file.
        column: 1-based column number, or None.
        key: dotted key path inside the document, e.g. ``serial.dh.rows[2].alpha``.
        message: what is wrong.
        fix: how to fix it.
    """

    file: str
    line: int | None
    column: int | None
    key: str
    message: str
    fix: str

    def __str__(self) -> str:
        where = self.file
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        key = f" at '{self.key}'" if self.key else ""
        return f"{where}:{key} {self.message}\n    fix: {self.fix}"


class ModelError(SymkinError):
    """A model file is malformed or inconsistent; holds every problem found."""

    def __init__(self, problems: list[Problem] | tuple[Problem, ...]):
        if not problems:
            raise ValueError("ModelError needs at least one problem")
        self.problems = tuple(problems)
        super().__init__(self._text())

    #: The message lists at most this many problems (a hostile file can have thousands).
    MAX_SHOWN = 20

    def _text(self) -> str:
        head = f"{len(self.problems)} problem(s) in the model:" if len(self.problems) > 1 else ""
        body = "\n".join(str(p) for p in self.problems[:self.MAX_SHOWN])
        if len(self.problems) > self.MAX_SHOWN:
            body += f"\n... and {len(self.problems) - self.MAX_SHOWN} more"
        return f"{head}\n{body}" if head else body


class NotApplicable(ValueError):
    """An analysis does not apply to this model (a serial arm asked for a parallel inverse, a solver that takes
    poses asked for positions...): the message says why.  Code that tries several analyses catches this one,
    never a bare ValueError, so that a real error inside an analysis is not taken for "does not apply"; the
    command line reports it as bad input (a ValueError)."""


class DerivationError(SymkinError):
    """A requested quantity cannot be derived for this model (e.g. FK of a model without joints)."""


class ModelDataError(DerivationError):
    """A requested quantity cannot be derived because of located data in the model file (a non-physical inertia
    that the kinematics do not use): bad input, exit 2, with the problems' places and fixes."""

    def __init__(self, problems: list[Problem] | tuple[Problem, ...]):
        self.problems = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems[:ModelError.MAX_SHOWN]))


class CacheTrustError(SymkinError):
    """The cache folder or its secret cannot be trusted (another user's, writable by others): refused with the fix."""


class GeneratedCodeError(SymkinError):
    """A directory of generated code is missing, incomplete or inconsistent with its manifest."""

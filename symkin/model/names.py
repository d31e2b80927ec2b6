"""Rules for the names a model gives to parameters, joints and links.

Names become Python and C identifiers in generated code, keys of manifests and parts of
output names such as ``base_T_link3``; so they are plain identifiers that start with a
letter (leading underscores are kept for generated temporaries) and are none of the
keywords and reserved words of the emitted languages.

The words of the languages symkin ships backends for are here, below the backends: the reader
refuses them with the file and line before any backend is chosen, and robot files' names are
renamed around them (:func:`code_names`).  Each backend declares the words its code cannot take
(:class:`symkin.backends.base.Backend`; the shipped ones these sets), which ``symkin derive``
checks for a backend added later.
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Iterable

from symkin.model.expressions import RESERVED_NAMES

IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")

PYTHON_KEYWORDS = frozenset(keyword.kwlist) | frozenset(keyword.softkwlist)

C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if "
    "inline int long register restrict return short signed sizeof static struct switch typedef "
    "union unsigned void volatile while _Bool _Complex _Imaginary bool true false NULL".split()
)

#: ECMAScript 2023 reserved words, strict-mode ones and the globals the JavaScript backend uses.
JS_KEYWORDS = frozenset(
    "await break case catch class const continue debugger default delete do else enum export extends "
    "false finally for function if import in instanceof new null return super switch this throw true try "
    "typeof var void while with yield let static implements interface package private protected public "
    "arguments eval undefined NaN Infinity Math Object Number Array module exports globalThis".split()
)

#: Words used by the generated code itself (inputs, modules, helpers).
_GENERATED_CODE_WORDS = frozenset(
    "numpy np math casadi ca out q qd qdd tau batch params self result base tcp world "
    "M V C G J".split()
)

RESERVED_IDENTIFIERS = (
    PYTHON_KEYWORDS | C_KEYWORDS | JS_KEYWORDS | _GENERATED_CODE_WORDS | RESERVED_NAMES
)


def name_problem(name: object) -> str | None:
    """Why ``name`` cannot name a model element, or None if it can."""
    if not isinstance(name, str):
        return f"a name must be a string, got {type(name).__name__}"
    if not IDENTIFIER.match(name):
        return (f"'{name}' is not a valid name (a letter, then up to 63 letters, digits or underscores)")
    if name in RESERVED_IDENTIFIERS:
        return f"'{name}' is a reserved word of symkin or of the generated code"
    return None


def code_names(names: Iterable[str], prefix: str) -> dict[str, str]:
    """{name: identifier} for the names of a robot file (URDF link and joint names are any text:
    ``joint_0.0``, ``/shoulder_link``, ``8``), so that vendor files derive unedited.

    The rule: a name that is already a valid model name (:func:`name_problem`) keeps it; any other
    becomes one: each run of characters other than ASCII letters, digits and ``_`` becomes ``_``,
    leading and trailing ``_`` go, a result that does not start with a letter gets ``prefix_`` in
    front, a reserved word gets a trailing ``_``, and it is cut to 60 characters.  A clash with a
    name taken before (valid names first, then the others in the given order) gets ``_2``, ``_3``...
    """
    names = list(dict.fromkeys(names))
    taken = {name for name in names if name_problem(name) is None}
    result = {name: name for name in taken}
    for name in names:
        if name in result:
            continue
        base = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_")
        if not base[:1].isalpha():
            base = f"{prefix}_{base}".rstrip("_")
        base = base[:60]
        if base in RESERVED_IDENTIFIERS:
            base += "_"
        candidate, k = base, 1
        while candidate in taken:
            k += 1
            candidate = f"{base}_{k}"
        taken.add(candidate)
        result[name] = candidate
    return result

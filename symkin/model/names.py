"""Rules for the names a model gives to parameters, joints and links.

Names become Python and C identifiers in generated code, keys of manifests and parts of
output names such as ``base_T_link3``; so they are plain identifiers that start with a
letter (leading underscores are kept for generated temporaries) and are none of the
keywords and reserved words of the emitted languages.
"""

from __future__ import annotations

import keyword
import re

from symkin.model.expressions import RESERVED_NAMES

IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,63}$")

_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if "
    "inline int long register restrict return short signed sizeof static struct switch typedef "
    "union unsigned void volatile while _Bool _Complex _Imaginary bool true false NULL".split()
)

#: ECMAScript 2023 reserved words, strict-mode ones and the globals the JavaScript backend uses.
_JS_KEYWORDS = frozenset(
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
    frozenset(keyword.kwlist) | frozenset(keyword.softkwlist) | _C_KEYWORDS | _JS_KEYWORDS | _GENERATED_CODE_WORDS | RESERVED_NAMES
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

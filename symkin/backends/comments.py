"""Free text in generated code: a model file's description, references, units and parameter docs
(hostile text: model files come from strangers) made inert in the comments and docstrings of every
backend.

Each function maps text to text that reads the same but cannot leave its comment or string:

* :func:`plain`: control, format (bidirectional overrides: "Trojan Source", CVE-2021-42574) and
  line/paragraph separator characters become spaces; every backend's text passes through it;
* :func:`block_comment`: for C and JavaScript ``/* ... */`` comments, which ``*/`` would close (and
  where ``/*`` draws a compiler warning); the
  JavaScript module is also inlined in the ``<script>`` of ``symkin view``'s page, where ``</``
  (``</script>``) and ``<!--`` would end or derail the script element, so those are broken too;
* :func:`docstring`: for Python docstrings (non-raw, triple double quotes): backslashes are
  doubled, so no escape sequence (``\\N{``, ``\\x``) forms, and quotes are escaped so that no
  ``\"\"\"`` ends the string.

Wrap first, then escape each line: a wrap never splits an escape sequence.
"""

from __future__ import annotations

import textwrap
import unicodedata
from collections.abc import Callable

#: Unicode general categories that never reach generated code: control (Cc), format (Cf), line and
#: paragraph separators (Zl, Zp: line terminators in JavaScript), surrogates (Cs).
_REMOVED_CATEGORIES = frozenset({"Cc", "Cf", "Zl", "Zp", "Cs"})


def plain(text: str, keep_newlines: bool = False) -> str:
    """``text`` with every control, format and separator character replaced by a space (``\\n`` kept
    if ``keep_newlines``)."""
    return "".join(" " if unicodedata.category(c) in _REMOVED_CATEGORIES and not (keep_newlines and c == "\n")
                   else c for c in text)


def block_comment(line: str) -> str:
    """One line of a ``/* ... */`` comment (C, JavaScript also inlined in HTML): no ``*/``, no ``/*`` (which
    compilers warn of), no ``</`` or ``<!--``."""
    return (plain(line).replace("*/", "* /").replace("/*", "/ *").replace("</", "<\\/")
            .replace("<!--", "<!-\\-"))


def docstring(line: str) -> str:
    """One line of a Python ``\"\"\"docstring\"\"\"``: backslashes doubled, double quotes in runs escaped."""
    escaped = plain(line).replace("\\", "\\\\")
    return escaped.replace('"""', '\\"\\"\\"') if '"""' in escaped else escaped


def docstring_lines(text: str) -> str:
    """:func:`docstring` on each line of ``text`` (newlines kept)."""
    return "\n".join(docstring(line) for line in plain(text, keep_newlines=True).split("\n"))


def wrapped(text: str, width: int, escape: Callable[[str], str]) -> list[str]:
    """``text`` wrapped to ``width`` and each line made inert by ``escape`` (:func:`block_comment`,
    :func:`docstring`): the one way every backend turns free text into comment or docstring lines."""
    return [escape(line) for line in textwrap.wrap(plain(text), width)]

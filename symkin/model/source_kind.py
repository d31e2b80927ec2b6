"""What kind of robot or model file a path holds, told by its content rather than its name.

A URDF named ``robot.xml`` is read as a URDF; a xacro file (``robot.urdf.xacro``, or a ``.urdf``
that still holds ``xacro:`` macros) is expanded by :mod:`symkin.model.xacro_source` and an MJCF
file (root element ``<mujoco>``) compiled by :mod:`symkin.model.mjcf_source`, instead of being
parsed as YAML (issue 29).  Only the first
:data:`SNIFF_BYTES` are read, as bytes; nothing in them is evaluated.
"""

from __future__ import annotations

import re
from pathlib import Path

#: Bytes read to find the root element: declarations, comments and a licence header fit.
SNIFF_BYTES = 65536
#: The first element of an XML text after its declaration, processing instructions and comments.
_ROOT = re.compile(rb"\A(?:\xef\xbb\xbf)?\s*(?:<\?.*?\?>\s*|<!--.*?-->\s*|<!DOCTYPE[^>\[]*(?:\[.*?\])?\s*>\s*)*"
                   rb"<([A-Za-z_][\w.:-]*)", re.S)
_XML = re.compile(rb"\A(?:\xef\xbb\xbf)?\s*<")
#: A xacro element (an expanded URDF may keep the xmlns:xacro declaration, and macros in comments: no macro).
_XACRO = re.compile(rb"<xacro:")
_COMMENT = re.compile(rb"<!--.*?(?:-->|\Z)", re.S)
#: The refusal of a xacro file (here when told by its content; by the URDF reader at its first macro).
#: The URDF reader's refusal of a xacro element it meets (past the sniffed bytes, or in URDF text given directly).
XACRO_MESSAGE = "a xacro element in a file read as a plain URDF (its first xacro macro lies past the first 64 kB)"
XACRO_FIX = "name the file .xacro (robot.urdf.xacro), so that symkin expands it as xacro"

URDF, XACRO, MJCF, YAML = "urdf", "xacro", "mjcf", "yaml"


def source_kind(path: str | Path) -> str:
    """``urdf``, ``xacro``, ``mjcf`` or ``yaml`` (anything that is not XML, also a missing file: the
    YAML reader then reports it)."""
    path = Path(path)
    try:
        if not path.is_file():  # a FIFO would block the sniffing open: the reader refuses what is no file
            raise FileNotFoundError(path)
        with open(path, "rb") as handle:
            head = handle.read(SNIFF_BYTES)
    except OSError:
        return XACRO if path.suffix.lower() == ".xacro" else URDF if path.suffix.lower() == ".urdf" else YAML
    root = _ROOT.match(head)
    if root is None:  # XML whose root we cannot see (the URDF reader names what is wrong), or not XML
        return XACRO if path.suffix.lower() == ".xacro" else URDF if _XML.match(head) else YAML
    if root.group(1) == b"mujoco":
        return MJCF
    if path.suffix.lower() == ".xacro" or _XACRO.search(_COMMENT.sub(b"", head)):
        return XACRO
    return URDF

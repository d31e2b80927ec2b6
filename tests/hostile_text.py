"""Hostile free text for the generated code and the pages symkin writes (issue 28): what a stranger's
model file or URDF may hold in its description, references, units, parameter docs and names.

Every payload that could run sets a marker its test looks for: ``PWNED`` in ``document.title``, a
``window``/``globalThis`` property starting with ``pwned``, or a file ``pwned`` in the working
directory.  :func:`model_text` puts one case into every free-text field of a model file,
:func:`urdf_text` into a URDF's robot name (the free text a URDF carries into the page), and a name
case into its joint and link names.
"""

from __future__ import annotations

import json

#: (id, text): at least 20 cases, each aimed at one way out of its context.
TEXT_CASES = [
    ("img-onerror", "<img src=x onerror=\"document.title='PWNED'\">"),
    ("script-element", "<script>window.pwnedScript = 1; document.title = 'PWNED'</script>"),
    ("close-script", "</script><script>window.pwnedClose = 1; document.title = 'PWNED'</script>"),
    ("close-script-case", "</SCRIPT ><img src=x onerror=\"window.pwnedCase = 1\">"),
    ("html-comment", "<!--<script>window.pwnedComment = 1</script>-->"),
    ("comment-then-script", "<!-- <script> </script><img src=x onerror=\"window.pwnedDouble = 1\">"),
    ("svg-onload", "<svg onload=\"window.pwnedSvg = 1\"></svg>"),
    ("attribute-double", "\"><img src=x onerror=\"window.pwnedAttr = 1\">"),
    ("attribute-single", "'><img src=x onerror='window.pwnedAttr2 = 1'>"),
    ("javascript-url", "javascript:window.pwnedUrl = 1; document.title = 'PWNED'"),
    ("iframe-javascript", "<iframe src=\"javascript:parent.pwnedFrame = 1\"></iframe>"),
    ("meta-refresh", "<meta http-equiv=\"refresh\" content=\"0; url=javascript:window.pwnedMeta = 1\">"),
    ("base-href", "<base href=\"javascript:window.pwnedBase = 1//\">"),
    ("style-hide", "<style>body { display: none !important }</style>"),
    ("line-separator", "end\u2028window.pwnedLs = 1; document.title = 'PWNED'; //"),
    ("paragraph-separator", "end\u2029window.pwnedPs = 1; //"),
    ("js-comment-close", "*/ globalThis.pwnedComment2 = 1; document.title = 'PWNED'; /*"),
    ("js-template", "${globalThis.pwnedTemplate = 1}`; globalThis.pwnedTick = 1; `"),
    ("python-docstring", "\"\"\"; open('pwned', 'w'); \"\"\""),
    ("python-escapes", "\\N{NOT A NAME} \\x \\u12 ends with a backslash \\"),
    ("c-line-splice", "//\\\nglobalThis.pwnedSplice = 1;"),
    ("jinja-template", "{{ 7 * 191 }} {% if true %}1337{% endif %} {#"),
    ("entities", "&lt;script&gt;window.pwnedEntity = 1&lt;/script&gt; &amp; &#x3c;b&#x3e;"),
    ("bidi-override", "safe \u202e;)1 = ssalCdenwp.wodniw\u202c text"),
    ("json-breakers", "\"}]}</script><script>window.pwnedJson = 1</script>{\"a\": [\"\\u2028"),
    ("long-text", " ".join(["<b>very long</b> text"] * 2000)),
    ("dunder-proto", "__proto__ constructor prototype toString"),
]

#: (id, name): names a model gives to parameters; the reader accepts only plain identifiers
#: (symkin/model/names.py), so each is either used as a name or refused with a located message.
NAME_CASES = [
    ("js-keyword", "function"),
    ("proto", "__proto__"),
    ("constructor", "constructor"),
    ("to-string", "toString"),
    ("has-own-property", "hasOwnProperty"),
    ("markup", "<b>l1</b>"),
    ("script-name", "l1</script>"),
]

#: What a payload may leave behind in a page (checked in the browser).
MARKER_PREFIX = "pwned"


def model_text(text: str, parameter: str = "l1") -> str:
    """A 2-DoF planar arm whose description, references and parameter docs all hold ``text`` (and whose first
    link length is named ``parameter``), as YAML (JSON is YAML).  A unit is no free text (issue 60: it is
    converted, an unknown one refused): tests/model/test_units.py."""
    model = {
        "name": "arm",
        "description": text,
        "references": [text, "a manufacturer's datasheet"],
        "parameters": {parameter: {"value": 0.1, "unit": "m", "doc": text},
                       "l2": {"value": 0.2, "unit": "m", "doc": text}, "m2": 0.5},
        "serial": {"dh": {"convention": "classic", "rows": [
            ["theta1", "R", 0, 0, parameter, 0],
            {"name": "theta2", "type": "R", "theta": 0, "d": 0, "a": "l2", "alpha": 0, "limits": ["-pi/2", "pi/2"]},
        ]}},
        "task_space": ["x", "y"],
        "bodies": [{"link": "link2", "mass": "m2"}],
    }
    return json.dumps(model, indent=1)


def urdf_text(robot_name: str, joint: str = "shoulder", link: str = "upper") -> str:
    """A 2-DoF URDF arm whose robot name is ``robot_name`` and whose first joint and link are named
    ``joint`` and ``link`` (each escaped as an XML attribute)."""
    from xml.sax.saxutils import quoteattr

    return f"""<?xml version="1.0"?>
<robot name={quoteattr(robot_name)}>
  <link name="base"/>
  <link name={quoteattr(link)}><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="lower"><inertial><mass value="0.5"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name={quoteattr(joint)} type="revolute"><parent link="base"/><child link={quoteattr(link)}/>
    <axis xyz="0 0 1"/><limit lower="-1.5" upper="1.5" effort="10" velocity="2"/></joint>
  <joint name="elbow" type="revolute"><parent link={quoteattr(link)}/><child link="lower"/><origin xyz="0.2 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-1.5" upper="1.5" effort="10" velocity="2"/></joint>
  <joint name="tool" type="fixed"><parent link="lower"/><child link="tip"/><origin xyz="0.2 0 0"/></joint>
</robot>
"""

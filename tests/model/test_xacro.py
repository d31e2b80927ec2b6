"""xacro input (issue 29): symkin's own expander (symkin/model/xacro_source.py) against the reference
``xacro`` package on every stock xacro file of Robotics Toolbox's data package (files nobody here wrote),
a derived and cross-checked xacro arm, and hostile expressions that must be refused, never run."""

from __future__ import annotations

import re
import xml.dom.minidom
from importlib.metadata import distribution
from pathlib import Path

import pytest

from symkin.errors import ModelError
from symkin.model import load_model
from symkin.model.xacro_source import expand_xacro

RTB = Path(distribution("rtb-data").locate_file("rtbdata"))
KUKA = RTB / "xacro/kuka_description"
#: The ROS packages the files find, named as a user names them (--xacro-package): rtb-data ships them without
#: their package.xml, and $(find) resolves only named packages or folders with a package.xml (issue 59).
PACKAGES = {f"kuka_{m}_support": KUKA / f"kuka_{m}" for m in
            ("kr3", "kr5", "kr6", "kr10", "kr16", "kr120", "kr150", "kr210", "lbr_iiwa")}
PACKAGES["abb_irb140"] = RTB / "xacro/abb_irb140_description"
PACKAGES.update({name: folder for folder in sorted(RTB.glob("xacro/**/")) if folder.is_dir()
                 for name in [folder.name] if name in ("kuka_resources", "qut_frankie_description",
                                                       "interbotix_gazebo", "trossen_gazebo", "lms1xx",
                                                       "ridgeback_description")})


def _elements(document: xml.dom.minidom.Node) -> list[tuple[str, tuple[tuple[str, str], ...]]]:
    """The elements in document order with their attributes (no xmlns), as the URDF reader sees them."""
    out = []
    for child in document.childNodes:
        if child.nodeType == child.ELEMENT_NODE:
            out.append((child.tagName, tuple(sorted((k, v) for k, v in child.attributes.items()
                                                    if not k.startswith("xmlns")))))
            out.extend(_elements(child))
    return out


def _reference(path: Path, monkeypatch: pytest.MonkeyPatch) -> list:
    """The reference xacro package's expansion ($(find) answered from PACKAGES or the file's neighbours)."""
    import xacro
    import xacro.substitution_args

    def find(package: str) -> str:
        if package in PACKAGES:
            return str(PACKAGES[package])
        for directory in [path.parent, *path.parents][:6]:  # ROS's package index: folders with a package.xml
            for candidate in [directory, *(p for p in directory.iterdir() if p.is_dir())]:
                manifest = candidate / "package.xml"
                if manifest.is_file() and f"<name>{package}</name>" in manifest.read_text():
                    return str(candidate)
        raise LookupError(package)

    monkeypatch.setattr(xacro.substitution_args, "_eval_find", find)
    return _elements(xacro.process_file(str(path)))


def test_stock_xacro_files_expand_as_the_reference_xacro_does(monkeypatch):
    """Every xacro file of rtb-data that the reference expands gives the same elements and attributes, to
    the character (numbers are printed as Python prints floats, as xacro does); the files the reference
    cannot expand (a missing package, an undefined name) are refused by symkin too, located."""
    import xacro

    files = sorted(RTB.rglob("*.xacro"))
    assert len(files) >= 55
    same = 0
    for path in files:
        try:
            want = _reference(path, monkeypatch)
        except (xacro.XacroException, LookupError):
            with pytest.raises(ModelError, match=r"\.xacro:\d+:\d+: "):
                expand_xacro(path, packages=PACKAGES)
            continue
        got = _elements(xml.dom.minidom.parseString(expand_xacro(path, packages=PACKAGES).text))
        assert got == want, path
        same += 1
    assert same >= 55


def test_a_xacro_arm_derives_and_crosschecks(tmp_path, capsys):
    """The Trossen PincherX 100 (rtb-data) derives unedited from its xacro, with its inertials, and agrees
    with Pinocchio reading the same expansion; --xacro-arg sets an argument (robot_name prefixes every
    link), and messages from the URDF reader point into the xacro file that wrote the element."""
    from symkin.references.crosscheck import crosscheck
    from symkin.cli import main

    px100 = RTB / "xacro/trossen_descriptions/urdf/px100.urdf.xacro"
    report = crosscheck(px100, samples=3, backends=("numpy",),
                        urdf={"tip": "/gripper_prop_link"})
    assert not report.failures, report.comparisons
    assert {"mass_matrix", "gravity_vector", "inverse_dynamics"} <= {c.quantity for c in report.comparisons}
    assert main(["check", str(px100), "--tip", "px/gripper_prop_link", "--chain", "--xacro-arg", "robot_name:=px"]) == 0
    out = capsys.readouterr().out
    assert "ok - model 'px100', 5 joints (waist:R," in out
    # the note on the clipped finger names the line of the xacro file that declares the joint, not of the expansion
    line = int(re.search(r"px100\.urdf\.xacro, line (\d+): joint 'left_finger' off the chain", out).group(1))
    assert '<joint name="left_finger"' in px100.read_text().splitlines()[line - 1]
    model = load_model(px100, tip="px/gripper_prop_link", chain=True, xacro_args={"robot_name": "px"})
    assert model.dof == 5
    assert model.source_names["links"]["px_gripper_prop_link"] == "px/gripper_prop_link"
    # an option of the wrong file kind, an undeclared argument, a missing package: exit 2, located
    yaml_model = Path("models/planar_2r.yaml")
    assert main(["check", str(yaml_model), "--xacro-arg", "a:=1"]) == 2
    assert "--xacro-arg applies to xacro files only" in capsys.readouterr().err
    assert main(["check", str(px100), "--xacro-arg", "colour:=red"]) == 2
    assert "--xacro-arg colour names no <xacro:arg> of the file" in capsys.readouterr().err
    kr6 = KUKA / "kuka_kr6/urdf/kr6r700sixx.xacro"
    assert main(["check", str(kr6)]) == 2
    err = capsys.readouterr().err
    assert f"{kr6}:4:3: cannot find the ROS package 'kuka_kr6_support'" in err
    assert "fix: pass --xacro-package kuka_kr6_support=DIRECTORY" in err
    assert main(["check", str(kr6), "--xacro-package", f"kuka_kr6_support={KUKA / 'kuka_kr6'}",
                 "--xacro-package", f"kuka_resources={KUKA / 'kuka_resources'}"]) == 0
    capsys.readouterr()
    # the URDF reader's messages land on the xacro element (here in the included hand.xacro)
    panda = RTB / "xacro/qut_frankie_description/robots/panda_arm_hand.urdf.xacro"
    with pytest.raises(ModelError, match=r"robots/hand\.xacro:\d+:\d+: at 'joint\[panda_finger_joint2\]\.mimic'"):
        load_model(panda, tip="panda_leftfinger", chain=True,  # the chain to one finger: the other mimics it from off the chain
                   xacro_packages={"qut_frankie_description": PACKAGES["qut_frankie_description"]})


ARM = """<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="length" default="0.3"/>
  <xacro:property name="l" value="$(arg length)"/>
  <xacro:property name="m" value="${2 * l}"/>
  <xacro:macro name="link" params="name mass:=1 *origin">
    <link name="${name}">
      <inertial><xacro:insert_block name="origin"/><mass value="${mass}"/>
        <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    </link>
  </xacro:macro>
  <link name="world"/>
  <xacro:link name="upper" mass="${m}"><origin xyz="${l/2} 0 0"/></xacro:link>
  <xacro:link name="fore"><origin xyz="${l/2} 0 0"/></xacro:link>
  <joint name="shoulder" type="revolute"><parent link="world"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="${-pi}" upper="${radians(180)}" effort="1" velocity="1"/></joint>
  <xacro:if value="${l &gt; 0.1}">
    <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
      <origin xyz="${l} 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  </xacro:if>
  BODY
</robot>
"""


def _arm(tmp_path: Path, body: str = "", name: str = "arm.urdf.xacro") -> Path:
    path = tmp_path / name
    path.write_text(ARM.replace("BODY", body))
    return path


def test_macros_properties_and_arguments_expand(tmp_path):
    """Lazy properties, a macro with a default and a block, xacro:if, math, $(arg) and its --xacro-arg."""
    arm = _arm(tmp_path)
    model = load_model(arm)
    assert [j.name for j in model.joints] == ["shoulder", "elbow"]
    text = expand_xacro(arm).text
    assert '<origin xyz="0.3 0 0"/>' in text
    assert '<origin xyz="0.15 0 0"/>' in text
    assert '<mass value="0.6"/>' in text
    assert [float(b.mass) for b in model.bodies] == [0.6, 1.0]
    with pytest.raises(ModelError, match="2 root links \\(world, fore\\)"):  # xacro:if dropped the elbow
        load_model(arm, xacro_args={"length": "0.1"})


#: Expressions that would run code, read the environment or exhaust memory under Python's eval.
HOSTILE = [
    ("${().__class__.__bases__[0].__subclasses__()}", "is not allowed in a xacro expression"),
    ("${__import__('os').system('touch PWNED')}", "'__import__' is not a defined property"),
    ("${[c for c in 'abc']}", "is not allowed in a xacro expression"),
    ("${(lambda: 1)()}", "is not allowed in a xacro expression"),
    ("${'a'.upper()}", "the attribute '.upper' is not allowed"),
    ("${str.format}", "the attribute '.format' is not allowed"),
    ("${'x' * 10**9}", "grows beyond"),
    ("${2 ** 10 ** 10}", "exceeds 1024"),
    ("${max(1, key=str)}", "is not allowed in a xacro expression"),
    ("$(env HOME)", "reads the environment"),
    ("${undefined_name}", "'undefined_name' is not a defined property"),
    ("${1 +}", "is not an expression"),
    ("${1", "has no closing"),
    # issue 59: every operation bounded by the size of its result before it is built
    ("${round(1, -10**9)}", "round to -1000000000 digits"),
    ("${(2 ** 1000) ** 1000}", "a power with more than 4096 bits"),
    ("${(7 ** 1000) * (7 ** 1000) * (7 ** 1000) * (7 ** 1000)}", "a product with more than 4096 bits"),
    ("${'%01000000000d' % 0}", "a format grows beyond"),
    ("${[[0] * 1000000] * 1000000}", "a value grows beyond 1000000 characters or items"),
    ("${str([[0] * 1000] * 100000)}", "a value grows beyond 1000000 characters or items"),
    ("${sum([[0] * 100] * 100, [])}", "sum with a start value other than a number"),
    ("${[1] * 999999 == [1] * 999999 and [[1] * 999] * 1002}", "grows beyond"),
    ("${" + "-" * 100000 + "1}", "nests too deeply"),
    ("${float('1' * 5000)}", "more than 400 characters"),
]


@pytest.mark.parametrize("text, message", HOSTILE)
def test_hostile_expressions_are_refused_located_and_never_run(tmp_path, monkeypatch, text, message):
    monkeypatch.chdir(tmp_path)
    arm = _arm(tmp_path, f'<link name="extra"><visual><origin xyz="{text}"/></visual></link>')
    with pytest.raises(ModelError) as raised:
        load_model(arm)
    assert message in str(raised.value), str(raised.value)
    assert f"{arm}:21:" in str(raised.value), str(raised.value)
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.parametrize("body, message", [
    ('<xacro:macro name="loop" params=""><xacro:loop/></xacro:macro><xacro:loop/>', "nest deeper than 100"),
    ('<xacro:property name="a" value="${b}"/><xacro:property name="b" value="${a}"/><link name="${a}"/>',
     "circular property definition"),
    ('<xacro:include filename="/etc/passwd"/>', "is not a .xacro/.urdf/.xml file"),
    # issue 59: element counts, macro fan-out and computed names
    ('<xacro:macro name="f" params="n"><xacro:if value="${n > 0}"><xacro:f n="${n-1}"/><xacro:f n="${n-1}"/>'
     '</xacro:if></xacro:macro><xacro:f n="60"/>', "more than 100000 macro calls"),
    ('<xacro:macro name="twice" params="*b"><xacro:insert_block name="b"/><xacro:insert_block name="b"/>'
     '</xacro:macro>' + '<xacro:twice>' * 20 + '<link name="x"/>' + '</xacro:twice>' * 20,
     "the expansion has more than 100000 elements"),
    ('<xacro:element xacro:name="link name=\'evil\'/&gt;&lt;link"/>', "is not an XML element name"),
    ('<link name="a"><xacro:attribute name="x=\'1\' y" value="2"/></link>', "is not an XML attribute name"),
    ('<a>' * 300 + '</a>' * 300, "the XML nests deeper than 200 elements"),
    ('<xacro:include filename="missing.xacro"/>', "cannot read"),
    ('<xacro:nothing/>', "no macro named 'nothing'"),
    ('<xacro:link name="x" colour="red"><origin/></xacro:link>', "macro 'link' has no parameter 'colour'"),
    ('<xacro:link><origin/></xacro:link>', "macro 'link' needs the parameter 'name'"),
    ('<xacro:if value="maybe"/>', "the condition 'maybe' is neither true nor false"),
    ('<xacro:property name="s" value="${\'x\' * 900000}"/><xacro:macro name="m" params=""><link name="${s}"/>'
     '<link name="${s}"/></xacro:macro><xacro:m/><xacro:m/><xacro:m/><xacro:m/><xacro:m/><xacro:m/>',
     "the expansion grows beyond 10000000 characters"),
])
def test_bad_xacro_gets_a_located_error(tmp_path, body, message):
    arm = _arm(tmp_path, body)
    with pytest.raises(ModelError) as raised:
        load_model(arm)
    assert message in str(raised.value), str(raised.value)
    assert f"{arm}:21:" in str(raised.value), str(raised.value)


def test_element_text_is_expanded_and_a_transmission_gives_the_gear_ratio(tmp_path):
    """A transmission's mechanicalReduction is element text, with ${...} like any attribute (issue 30)."""
    arm = _arm(tmp_path, '<transmission name="t"><type>transmission_interface/SimpleTransmission</type>'
                         '<joint name="elbow"/><actuator name="m"><mechanicalReduction>${2 * l * 100}'
                         '</mechanicalReduction></actuator></transmission>')
    model = load_model(arm)
    assert [(a.joint, float(a.gear_ratio)) for a in model.actuators] == [("elbow", 60.0)]

"""MJCF input (issue 29): MuJoCo's compiler reads the file, symkin derives the chain, and both references
agree - Pinocchio on the URDF text symkin generates, MuJoCo on the file itself (M with armature, and
qfrc_bias = V + G) - on the MJCF models that ship with gymnasium and on a file written to exercise
what MJCF allows beyond URDF."""

from __future__ import annotations

from importlib.metadata import distribution
from pathlib import Path

import pytest

from symkin.references.crosscheck import crosscheck
from symkin.cli import main
from symkin.errors import ModelError
from symkin.model import load_model
from tolerances import CLOSED_FORM

ASSETS = Path(distribution("gymnasium").locate_file("gymnasium/envs/mujoco/assets"))

#: joints along hinges and slides about tilted axes through offset anchors, two and one per body, with
#: ref (the model pose is at q = ref), a full inertia tensor (principal axes by MuJoCo), gravity off
#: the z axis, armature, damping and frictionloss from defaults and per joint.
ODD = """<mujoco model="odd">
  <compiler angle="radian"/>
  <option gravity="0.5 -1 -9"/>
  <default><joint damping="0.2" armature="0.01"/></default>
  <worldbody>
    <body name="base" pos="0.1 0.2 0.3" quat="0.9 0.1 0.3 -0.2">
      <joint name="slide" type="slide" axis="0.3 0.4 0.866" ref="0.05" range="-0.5 0.5"/>
      <geom type="box" size="0.05 0.04 0.03" mass="1.3"/>
      <body name="arm" pos="0 0.1 0.05" euler="0.3 -0.2 0.5">
        <joint name="a1" type="hinge" pos="0.02 0 0.01" axis="0 0 1" ref="0.4"/>
        <joint name="a2" type="hinge" pos="-0.03 0.02 0" axis="1 1 0" frictionloss="0.1"/>
        <inertial pos="0.1 0.02 -0.01" mass="0.7" fullinertia="0.01 0.02 0.015 0.001 -0.002 0.003"/>
        <body name="hand" pos="0.2 0 0" quat="0.7 0 0.7 0">
          <joint name="a3" type="hinge" pos="0 0.01 0" axis="0 1 0" range="-2 2"/>
          <geom type="capsule" fromto="0 0 0 0.1 0.02 0" size="0.02" mass="0.3"/>
          <body name="tip" pos="0.1 0.02 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _passes_both(report) -> None:
    rows = {c.quantity for c in report.comparisons}
    assert {"mass_matrix", "inverse_dynamics", "mass_matrix (MuJoCo)",
            "coriolis_vector + gravity_vector (MuJoCo)"} <= rows, rows
    assert not report.failures, report.comparisons


@pytest.mark.parametrize("file, tip", [("reacher.xml", "fingertip"), ("pusher.xml", "tips_arm"),
                                       ("inverted_double_pendulum.xml", None), ("hopper.xml", "foot"),
                                       ("walker2d_v5.xml", None)])
def test_gymnasium_models_agree_with_mujoco_and_pinocchio(file, tip):
    """As shipped: reacher and pusher carry armature (the drives' reflected inertia), the hopper's chain
    starts with two slides and a hinge at the root; the objects and targets beside them are locked.  The planar
    walker is read with no flag (issue 61: the whole tree, a slide-slide-hinge root carrying two legs)."""
    report = crosscheck(ASSETS / file, samples=3, backends=("numpy",), coriolis_matrix=False,
                        urdf={"tip": tip} if tip else {})
    _passes_both(report)
    assert "MuJoCo" in report.reference


def test_what_mjcf_allows_beyond_urdf_reads_right(tmp_path):
    path = tmp_path / "odd.xml"
    path.write_text(ODD)
    model = load_model(path)
    assert [j.name for j in model.joints] == ["slide", "a1", "a2", "a3"]
    assert [(a.joint, float(a.reflected_inertia)) for a in model.actuators] == [(j, 0.01) for j in
                                                                               ("slide", "a1", "a2", "a3")]
    _passes_both(crosscheck(path, samples=3, backends=("numpy",)))


def test_bad_mjcf_gets_located_errors(tmp_path, capsys):
    ant = ASSETS / "ant.xml"
    with pytest.raises(ModelError, match=r"ant\.xml:\d+:\d+: at 'joint\[root\]' joint 'root' on the chain world -> "
                                         r"body4 is a free joint"):
        load_model(ant, tip="body4", chain=True)
    # below the free joint, a leg is a chain (the other legs' joints locked)
    assert load_model(ant, base="torso", tip="body4", chain=True).dof == 2
    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco><worldbody><body name="b"><joint type="hinge" bogus="1"/></body></worldbody></mujoco>')
    out = tmp_path / "out"
    assert main(["derive", str(bad), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}: MuJoCo's compiler refuses the file: XML Error: Schema violation: unrecognized attribute: " \
           "'bogus'" in err
    assert not out.exists()
    assert main(["derive", str(ASSETS / "reacher.xml"), "--tip", "fingertip", "--chain", "--only", "fk,mass_matrix",
                 "-o", str(out), "-q"]) == 0
    assert (out / "reacher" / "manifest.json").exists()


COUPLED = """<mujoco model="coupled">
  <compiler angle="radian"/>
  <worldbody>
    <body name="a" pos="0 0 0.1">
      <joint name="j1" type="hinge" axis="0 0 1" range="-2 2"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="1"/>
      <body name="b" pos="0.3 0 0">
        <joint name="j2" type="hinge" axis="0 1 0" ref="0.2" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02" mass="0.7"/>
        <body name="c" pos="0.25 0 0">
          <joint name="j3" type="hinge" axis="0 1 0" range="-3 3"/>
          <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.02" mass="0.3"/>
          <body name="tip" pos="0.1 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality><joint joint1="j3" joint2="j2" polycoef="0.1 -1 0 0 0"/></equality>
  <tendon><fixed name="t"><joint joint="j1" coef="1"/></fixed></tendon>
</mujoco>
"""


def test_a_joint_equality_is_a_coupling_and_other_constraints_are_noted(tmp_path):
    """MuJoCo's affine joint equality q3 - ref3 = c0 + c1 (q2 - ref2) is the coupling q3 = c1 q2 + b (one coordinate
    less), checked against MuJoCo's open-tree M and bias projected on the coordinates (A^T M A); a tendon is
    noted as not modelled."""
    path = tmp_path / "coupled.xml"
    path.write_text(COUPLED)
    model = load_model(path)
    assert model.dof == 2
    assert model.joints[2].coupling.leader == "j2"
    assert float(model.joints[2].coupling.offset) == pytest.approx(0.1 + 0.2, rel=CLOSED_FORM)
    assert any("tendon" in note for note in model.notes)
    _passes_both(crosscheck(path, samples=3, backends=("numpy",)))


def test_option_flags_that_change_the_model_are_honoured_or_noted(tmp_path):
    """Issue 61: <flag gravity="disable"/> was read with gravity on (V + G 0.76 off MuJoCo's): gravity, damping and
    frictionloss switched off are absent from the model and it agrees with MuJoCo (its bias V + G has no gravity);
    a disabled joint limit is noted, each flag once."""
    path = tmp_path / "flagged.xml"
    path.write_text(ODD.replace('<option gravity="0.5 -1 -9"/>', '<option gravity="0.5 -1 -9"><flag gravity="disable" '
                                'damper="disable" frictionloss="disable" limit="disable"/></option>'))
    model = load_model(path)
    assert model.gravity == (0, 0, 0)
    assert all(f.viscous == 0 and f.coulomb == 0 for f in model.friction)
    flags = [note for note in model.notes if note.startswith("MJCF <option><flag")]
    assert [note.split("<flag ")[1].split("=")[0] for note in flags] == ["gravity", "damper", "frictionloss", "limit"]
    report = crosscheck(path, samples=3, backends=("numpy",), coriolis_matrix=False)
    assert "coriolis_vector + gravity_vector (MuJoCo)" in {c.quantity for c in report.comparisons}
    assert not report.failures, report.comparisons


def test_forces_symkin_does_not_model_are_named_in_the_notes(tmp_path):
    """Issue 61: what MuJoCo applies beyond the rigid bodies - fluid forces of a medium (gymnasium's swimmer swims in
    one), gravity compensation of bodies - is said in the model's notes, named, not left out unseen."""
    swimmer = load_model(ASSETS / "swimmer.xml")
    assert any("density=4000.0, viscosity=0.1" in note and "fluid forces" in note for note in swimmer.notes)
    path = tmp_path / "compensated.xml"
    path.write_text(ODD.replace('<body name="hand"', '<body name="hand" gravcomp="1"'))
    assert any(note.startswith("bodies hand have gravcomp") for note in load_model(path).notes)

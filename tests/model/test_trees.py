"""Trees (issue 30): a serial model may branch - a torso carrying two arms and a head - with the TCP on a
chosen link. M, V, G and tau are those of the whole tree (against Pinocchio on the URDF symkin exports);
joints on other branches do not move the TCP nor couple in M; a bad parent or tip is a located error."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from symkin.references.crosscheck import crosscheck
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import model_from_text
from sample_models import TORSO
from tolerances import KINEMATICS



def test_a_two_arm_torso_agrees_with_pinocchio_on_the_whole_tree(tmp_path):
    path = tmp_path / "torso.yaml"
    path.write_text(TORSO)
    report = crosscheck(path, samples=3, backends=("numpy",))
    rows = {c.quantity for c in report.comparisons}
    assert {"fk", "frame r_fore", "frame head", "jacobian_geometric", "mass_matrix", "coriolis_vector",
            "gravity_vector", "inverse_dynamics", "coriolis_matrix C qd"} <= rows, rows
    assert not report.failures, report.comparisons


def test_branches_do_not_move_the_tcp_nor_couple_in_m():
    model = model_from_text(TORSO)
    d = Derivation(model)
    J = sympy.Matrix(d["jacobian_geometric"].expanded_outputs()[0])
    M = sympy.Matrix(d["mass_matrix"].expanded_outputs()[0])
    names = [j.name for j in model.joints]
    left, right, head = names[1:4], names[4:6], names[6:]
    for k, name in enumerate(names):
        assert (J[:, k] == sympy.zeros(6, 1)) == (name in right + head), name
    for a, b in [(x, y) for x in left for y in right + head] + [(x, y) for x in right for y in head]:
        assert M[names.index(a), names.index(b)] == 0, (a, b)
    assert M[0, 1] != 0
    assert M[0, 4] != 0  # the waist carries every branch


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("parent: chest, origin: {xyz: [0, 0, 0.45]}", "parent: r_hand, origin: {xyz: [0, 0, 0.45]}"),
     "joint 'head' hangs on 'r_hand', no link of the chain"),
    (lambda t: t.replace("{name: l_shoulder, parent: chest,", "{name: l_shoulder, parent: head,"),
     "joint 'l_shoulder' hangs on 'head', a link declared after it"),
    (lambda t: t.replace("tip: l_hand", "tip: r_hand"), "the tip 'r_hand' is not a link of the chain"),
])
def test_a_bad_tree_is_a_located_error(edit, message):
    with pytest.raises(ModelError, match=message) as error:
        model_from_text(edit(TORSO), file="torso.yaml")
    assert "torso.yaml:" in str(error.value)


def test_a_branch_on_the_base_starts_at_the_base_frame():
    """parent: base starts a second chain at the base's fixed operations (a second arm on the same table)."""
    text = TORSO.replace("{name: head, parent: chest,", "{name: head, parent: base,")
    model = model_from_text(text)
    d = Derivation(model)
    frames = d["frames"].expanded_outputs()
    head = frames[[o.name for o in d["frames"].outputs].index("base_T_head")]
    T = np.array(sympy.Matrix(head).subs({s: 0 for s in sympy.Matrix(head).free_symbols}), dtype=float)
    np.testing.assert_allclose(T[:3, 3], [0, 0, 0.8 + 0.45], atol=KINEMATICS * 1.25)  # reach 1.25 m


def test_the_manifest_and_the_viewer_know_the_tree(tmp_path):
    """The manifest records each joint's parent and the TCP's link (chains keep their manifest as it was), and
    the viewer's page draws each link from its parent."""
    import json

    from symkin.cli import main

    path = tmp_path / "torso.yaml"
    path.write_text(TORSO.replace("task_space: pose", "task_space: position"))
    assert main(["derive", str(path), "--only", "fk,frames,jacobian", "--backend", "numpy,js", "-o",
                 str(tmp_path / "out"), "-q"]) == 0
    manifest = json.loads((tmp_path / "out" / "torso" / "manifest.json").read_text())
    assert manifest["model"]["tree"] == {"parents": [-1, 0, 1, 2, 0, 4, 0], "tip": 3}
    assert main(["view", str(tmp_path / "out" / "torso"), "-o", str(tmp_path / "torso.html"), "--workspace",
                 "32"]) == 0
    assert '"tree":{"parents":[-1,0,1,2,0,4,0],"tip":3}' in (tmp_path / "torso.html").read_text()


def test_a_stock_two_arm_robot_is_one_tree(capsys):
    """Baxter as shipped (example-robot-data) with --branch: both arms move, their grippers and head locked, the
    TCP on the left hand; Pinocchio reads the whole file with the same joints locked. On the command line,
    --branch of an unknown link is a located error."""
    from symkin.cli import main
    from sample_models import ROBOTS_DIR

    baxter = ROBOTS_DIR / "baxter_description/urdf/baxter.urdf"
    report = crosscheck(baxter, samples=2, backends=("numpy",), urdf={"tip": "left_hand_link",
                                                                     "branches": ("right_hand_link",)})
    assert not report.failures, report.comparisons
    assert {"frame right_lower_forearm", "frame left_wrist", "mass_matrix", "inverse_dynamics"} <= \
        {c.quantity for c in report.comparisons}
    assert main(["check", str(baxter), "--tip", "left_hand_link", "--branch", "right_hand"]) == 2
    assert "the branch link 'right_hand' is not a link of the robot" in capsys.readouterr().err

"""Bad model files: a located error (file, line, key, fix), exit code 2, nothing written, nothing run."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from conftest import SYMKIN_CLI

from symkin.cli import main
from symkin.errors import ModelError
from symkin.model import load_model

#: The valid model the bad ones are made from (shared with the hostile corpus and the fuzz strategies).
VALID = (Path(__file__).resolve().parents[1] / "corpus" / "base_model.yaml").read_text()

# (case id, text to replace, replacement, expected line, expected key fragment, expected message fragment)
CASES = [
    ("unknown joint type", "[theta1, R,", "[theta1, Q,", 10, "serial.dh.rows[0].type", "unknown joint type"),
    ("multi-dof joint in a serial chain", "[theta1, R,", "[theta1, S,", 10, "rows[0].type", "several degrees of freedom"),
    ("dh row of the wrong length", "[theta1, R, 0, 0, l1, 0]", "[theta1, R, 0, 0, l1]", 10, "serial.dh.rows[0]",
     "a DH row has 6 entries"),
    ("undefined parameter", "a: l2,", "a: l3,", 11, "serial.dh.rows[1].a", "undefined name 'l3'"),
    ("non-numeric value", "l2: 0.2", "l2: abc", 4, "parameters.l2", "undefined name 'abc'"),
    ("boolean value", "l2: 0.2", "l2: yes", 4, "parameters.l2", "boolean"),
    ("duplicate key", "  m2: 0.5\n", "  m2: 0.5\n  l1: 0.3\n", 6, "parameters.l1", "duplicate key 'l1'"),
    ("duplicate joint name", "name: theta2", "name: theta1", 6, "serial", "duplicate joint name 'theta1'"),
    ("code in an expression", "a: l2,", "a: \"__import__('os').system('touch pwned')\",", 11, "rows[1].a",
     "invalid expression"),
    ("attribute access", "a: l2,", "a: l2.__class__,", 11, "rows[1].a", "unexpected character '.'"),
    ("yaml python tag", "l2: 0.2", "l2: !!python/object/apply:os.system ['touch pwned']", 4, "parameters.l2",
     "not allowed"),
    ("unknown key", "task_space: [x, y]", "task_spaces: [x, y]", 12, "task_spaces", "did you mean 'task_space'"),
    ("unknown link in a body", "{link: link2,", "{link: link9,", 14, "bodies[0].link", "unknown link"),
    ("limits reversed", "limits: [-pi, pi]", "limits: [pi, -pi]", 11, "rows[1].limits", "not below"),
    ("huge exponent", "l2: 0.2", "l2: 9**9**9", 4, "parameters.l2", "too large"),
    ("huge literal product (issue 59)", "m2: 0.5", "m2: 1e300*1e300*1e300", 5, "parameters.m2", "too large"),
    ("tiny literal quotient (issue 59)", "l2: 0.2", "l2: 1e-300/1e300", 4, "parameters.l2", "too small"),
    ("negative mass", "m2: 0.5", "m2: -0.5", 14, "bodies[0].mass", "negative mass m2 (-0.5 at the default values)"),
    ("name clash with a joint symbol", "  m2: 0.5\n", "  m2: 0.5\n  theta1_d: 1\n", 6, "parameters.theta1_d",
     "clashes with the symbol 'theta1_d' of joint 'theta1'"),
    ("reserved name", "l2: 0.2", "lambda: 0.2", 4, "parameters.lambda", "reserved word"),
    ("yaml syntax", "task_space: [x, y]", "task_space: [x, y", 13, "", "(opened at line 12)"),
    ("unknown scene output", "task_space: [x, y]", "task_space: [x, y]\nscene: {outputs: [fk, jacobain]}", 13,
     "scene.outputs[1]", "unknown output 'jacobain'"),
    ("home of the wrong length", "serial:\n  dh:", "serial:\n  home: [0]\n  dh:", 7, "serial.home",
     "expected 2 joint coordinates [theta1, theta2]"),
    ("home outside the limits", "serial:\n  dh:", "serial:\n  home: [0, 4]\n  dh:", 7, "serial.home[1]",
     "the home value 4 of 'theta2' lies outside its limits"),
]


def _write(tmp_path: Path, case: str, old: str, new: str) -> Path:
    assert old in VALID, case
    path = tmp_path / "arm.yaml"
    path.write_text(VALID.replace(old, new, 1))
    return path


def test_the_valid_base_model_loads(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(VALID)
    model = load_model(path)
    assert [j.name for j in model.joints] == ["theta1", "theta2"]


@pytest.mark.parametrize("case,old,new,line,key,message", CASES, ids=[c[0] for c in CASES])
def test_bad_model_is_reported_with_location_and_fix_and_nothing_is_written(tmp_path, case, old, new, line, key,
                                                                             message, capsys, monkeypatch):
    """The CLI in this process (a fresh process's exit code 2: the tests below; planted code in a fresh process:
    tests/model/test_hostile_corpus.py) - a second apiece instead of a Python start-up per case."""
    path = _write(tmp_path, case, old, new)
    out = tmp_path / "out"
    monkeypatch.chdir(tmp_path)
    code = main(["derive", str(path), "-o", str(out)])
    stderr = capsys.readouterr().err
    assert code == 2, stderr
    assert f"{path}:{line}" in stderr, stderr
    assert key in stderr
    assert message in stderr
    assert "fix:" in stderr
    assert not out.exists()
    assert not (tmp_path / "pwned").exists()


def test_every_problem_of_a_file_is_reported_at_once(tmp_path):
    text = VALID.replace("a: l2,", "a: l3,").replace("[theta1, R,", "[theta1, Q,")
    path = tmp_path / "arm.yaml"
    path.write_text(text)
    with pytest.raises(ModelError) as err:
        load_model(path)
    keys = {p.key for p in err.value.problems}
    assert {"serial.dh.rows[0].type", "serial.dh.rows[1].a"} <= keys


def test_derived_parameter_cycle_is_reported(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(VALID.replace("  m2: 0.5\n", "  m2: 0.5\n  u: {expr: v + 1}\n  v: {expr: 2*u}\n"))
    with pytest.raises(ModelError, match="cycle: u -> v -> u|cycle: v -> u -> v"):
        load_model(path)


def test_derived_parameters_are_inlined(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(VALID.replace("l2: 0.2", "l2: {expr: l1/2}"))
    model = load_model(path)
    assert [p.name for p in model.parameters] == ["l1", "m2"]
    l1 = model.parameter("l1").symbol
    assert any(op.vector[0] == l1 / 2 for op in model.joints[1].after)


def test_unphysical_inertia_blocks_only_the_outputs_that_use_it(tmp_path):
    """Issue 61: the Allegro hand's inertias break the triangle inequality and symkin refused even fk and J. The
    model loads with a note; every emitted quantity is derived: the kinematics are, and exactly INERTIA_OUTPUTS are
    refused with the located message and the fix (symkin check refuses a scene asking for one)."""
    from symkin.derivation import Derivation, catalog
    from symkin.dynamics.physical import INERTIA_OUTPUTS
    from symkin.errors import DerivationError

    path = tmp_path / "arm.yaml"
    path.write_text(VALID.replace("{link: link2, mass: m2}", "{link: link2, mass: m2, inertia: {xx: 0, yy: 4, zz: 3}}")
                    + "gravity: [0, -9.81, 0]\n")
    model = load_model(path)
    assert "the outputs that use the inertias (M, V, G, tau, regressors) are refused" in model.notes[-1]
    d = Derivation(model)
    blocked = set()
    for name in catalog.emitted_quantities("serial"):
        try:
            d[name]
        except DerivationError as err:
            if "not physical" in str(err):
                assert f"{path}:14:" in str(err)
                assert "--allow-nonphysical" in str(err)
                blocked.add(name)
    assert {"fk", "jacobian", "frames"} <= set(d.computed)
    assert blocked == set(INERTIA_OUTPUTS)
    from symkin.cli import main

    assert main(["check", str(path)]) == 0                             # its scene: fk and J
    path.write_text(path.read_text() + "scene:\n  outputs: [fk, mass_matrix]\n")
    assert main(["check", str(path)]) == 2                             # what derive would refuse


def test_unphysical_inertia_is_accepted_with_a_note_when_allowed(tmp_path):
    """Issue 29: the model key or the load_model option accepts it; the note says where and what."""
    bad = VALID.replace("{link: link2, mass: m2}", "{link: link2, mass: m2, inertia: {xx: 0, yy: 4, zz: 3}}")
    path = tmp_path / "keyed.yaml"
    path.write_text("allow_nonphysical: true\nnotes: [inertia from the vendor's CAD]\n" + bad)
    keyed = load_model(path)
    assert keyed.notes[0] == "inertia from the vendor's CAD"
    assert "line 16, at 'bodies[0].inertia': the inertia tensor is not physical" in keyed.notes[1]
    path = tmp_path / "option.yaml"
    path.write_text(bad)
    (note,) = load_model(path, allow_nonphysical=True).notes
    assert note == keyed.notes[1].replace("line 16,", "line 14,")  # two lines fewer above it
    path.write_text("allow_nonphysical: 1\n" + bad)
    with pytest.raises(ModelError, match="expected true or false"):
        load_model(path)
    # rounding in a file is not a violation: a lone product of inertia of 1e-35 on a 0.5 kg body
    path.write_text(VALID.replace("{link: link2, mass: m2}", "{link: link2, mass: m2, com: [0.1, 0, 0], "
                                                              "inertia: {xx: 0, yy: 0, zz: 0, xz: 1.0e-35}}"))
    assert load_model(path).notes == ()


def test_billion_laughs_fails_fast(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [*a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, *a{i - 1}, "
              f"*a{i - 1}, *a{i - 1}, *a{i - 1}]" for i in range(1, 9)]
    path = tmp_path / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ModelError, match="expands to more than"):
        load_model(path)


def test_missing_file_is_a_clean_error(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["check", str(tmp_path / "nope.yaml")], capture_output=True, text=True)
    assert result.returncode == 2
    assert "cannot read the file" in result.stderr


def test_one_bad_model_among_good_ones_writes_nothing(tmp_path):
    good = Path(__file__).resolve().parents[2] / "models" / "planar_2r.yaml"
    bad = _write(tmp_path, "bad", "a: l2,", "a: l3,")
    out = tmp_path / "out"
    result = subprocess.run(SYMKIN_CLI + ["derive", str(good), str(bad), "-o", str(out)], capture_output=True,
                            text=True)
    assert result.returncode == 2
    assert not out.exists()

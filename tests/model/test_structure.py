"""Mobility (seed eqs. 8.1-8.4) and the topology synthesis of sec. 2.2.2 (Tables 8.1/8.2, reconstructed)."""

from __future__ import annotations

import json
import subprocess
import textwrap
from fractions import Fraction

import pytest

from conftest import EXAMPLE_MODELS, MODELS_DIR, SYMKIN_CLI
from symkin.model import model_from_text
from symkin.structure.mobility import (bodies_of_legs, degree_of_parallelism, gruebler, joint_dof_budget,
                                       model_mobility, parallelism_class)
from symkin.structure.synthesis import leg_topologies, synthesize

INTENDED = {"planar_2r": 2, "ur10e": 6, "ur10e_classic": 6, "delta": 3, "stewart": 6, "pantograph": 2, "agile_eye": 3,
            "delta_wrist": 6, "phantom_premium": 3}


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_mobility_of_every_example_model_is_its_intended_dof(name, models):
    model = models[name]
    report = model_mobility(model)
    wrist = model.parallel.wrist if model.parallel is not None else None
    wrist_dof = 0 if wrist is None else len(wrist.coordinates)  # a hybrid device moves by its legs and its wrist
    assert report.mobility == report.intended == INTENDED[name] == model.dof + wrist_dof


def test_mobility_terms_of_the_parallel_examples(models):
    delta = model_mobility(models["delta"])
    assert (delta.lam, delta.bodies, delta.joints, sum(delta.joint_dofs), delta.identical) == (6, 8, 9, 15, 0)
    assert delta.parallelism == 1
    assert delta.budget == 15  # the seed's 15 joint DoF for the DELTA
    stewart = model_mobility(models["stewart"])
    assert (stewart.bodies, stewart.joints, sum(stewart.joint_dofs), stewart.identical) == (14, 18, 36, 0)


def test_gruebler_formula_and_its_corollaries():
    # Seed eq. 8.2 and its examples: 3-RUU, 6-UPS, 6-SPS (six idle rod spins), a four-bar (planar).
    assert gruebler(6, bodies_of_legs(9, 3), [1, 2, 2] * 3) == 3
    assert gruebler(6, bodies_of_legs(18, 6), [2, 1, 3] * 6) == 6
    assert gruebler(6, bodies_of_legs(18, 6), [3, 1, 3] * 6, identical=6) == 6
    assert gruebler(3, 4, [1, 1, 1, 1]) == 1
    # A closed loop of six revolute joints: rigid by eq. 8.2 (F = 0) unless its axes are constrained, e.g.
    # all parallel, when it moves as a planar loop with F = 3 (lambda = 3 gives the same).
    assert gruebler(6, 6, [1] * 6) == 0
    assert gruebler(6, 6, [1] * 6, constraints=3) == gruebler(3, 6, [1] * 6) == 3
    assert bodies_of_legs(9, 3) == 8  # eq. 8.3
    assert joint_dof_budget(3, 3) == 15
    assert joint_dof_budget(6, 6) == 36  # eq. 8.4
    assert degree_of_parallelism(3, 3) == 1
    assert parallelism_class(Fraction(2, 3)) == "partially parallel"
    assert parallelism_class(Fraction(4, 3)) == "highly parallel"


def test_idle_rods_between_spherical_joints_count_as_identical_conditions(models):
    text = (MODELS_DIR / "stewart.yaml").read_text().replace("{name: ub, type: U, axes: [[0, 0, 1], [0, 1, 0]]}",
                                                             "{name: ub, type: S}")
    sps = model_from_text(text)
    report = model_mobility(sps)
    assert sum(report.joint_dofs) == 42
    assert report.identical == 6
    assert report.mobility == 6


def test_declared_identical_conditions_and_constraints_enter_eq_8_2():
    text = textwrap.dedent("""\
        parallel:
          motion: translation
          mobility: {identical: 1, constraints: 2}
          legs:
            - {joints: [{name: a, type: R, axis: [0, 0, 1], active: true}, {name: b, type: U}, {name: c, type: U}],
               base: {radius: 1, angle: 0}, platform: {radius: 0.1, angle: 0}}
            - {joints: [{name: a, type: R, axis: [0, 0, 1], active: true}, {name: b, type: U}, {name: c, type: U}],
               base: {radius: 1, angle: 2}, platform: {radius: 0.1, angle: 2}}
            - {joints: [{name: a, type: R, axis: [0, 0, 1], active: true}, {name: b, type: U}, {name: c, type: U}],
               base: {radius: 1, angle: 4}, platform: {radius: 0.1, angle: 4}}
        """)
    report = model_mobility(model_from_text(text, name="m"))
    assert (report.identical, report.constraints, report.mobility) == (1, 2, 4)


def test_table_8_1_enumerates_every_five_dof_leg():
    legs = list(leg_topologies(5))
    assert len(legs) == len(set(legs)) == 136
    dofs = {"R": 1, "P": 1, "U": 2, "C": 2, "S": 3}
    assert all(sum(dofs[j] for j in leg) == 5 for leg in legs)
    synthesis = synthesize(3, 3)
    counts = {}
    for v in synthesis.verdicts:
        counts[v.distribution] = counts.get(v.distribution, 0) + 1
    assert counts == {"1+1+1+1+1": 32, "2+1+1+1": 64, "2+2+1": 24, "3+1+1": 12, "3+2": 4}


def test_synthesis_reproduces_the_six_surviving_topologies():
    synthesis = synthesize(dof=3, legs=3)
    assert (synthesis.budget, synthesis.leg_dof) == (15, 5)
    assert sorted(synthesis.survivors) == sorted(["UPU", "PUU", "CUR", "CRU", "RUU", "RUC"])


#: Every 2+2+1 topology the synthesis removes and the criterion that removes it (Table 8.2, that row).
ELIMINATED_221 = {
    "RCU": "strut", "RCC": "rotations", "PUC": "rotations", "PCU": "rotations", "PCC": "rotations",
    "URU": "actuator", "URC": "actuator", "UPC": "rotations", "UUR": "actuator", "UUP": "actuator",
    "UCR": "strut", "UCP": "rotations", "CRC": "rotations", "CPU": "rotations", "CPC": "rotations",
    "CUP": "rotations", "CCR": "rotations", "CCP": "rotations",
}


def test_every_eliminated_topology_has_the_criterion_that_removed_it():
    synthesis = synthesize(3, 3)
    verdicts = {v.topology: v for v in synthesis.verdicts}
    assert {t: v.eliminated_by.key for t, v in verdicts.items()
            if v.distribution == "2+2+1" and v.eliminated_by} == ELIMINATED_221
    # Spherical joints go first (Carricato's first rule), then the T5 rotation count, ...
    assert all(verdicts[t].eliminated_by.key == "spherical" for t in verdicts if "S" in t)
    assert verdicts["RRPPP"].eliminated_by.key == "rotations"
    # ... and every four- and five-joint leg that is a TPM leg and can be actuated concentrates.
    assert verdicts["RRRRR"].eliminated_by.key == "concentration"
    assert verdicts["RURP"].eliminated_by.key == "concentration"
    assert verdicts["URRR"].eliminated_by.key == "actuator"
    assert all(v.eliminated_by is not None for v in synthesis.verdicts if len(v.topology) > 3)
    groups = {v.eliminated_by.group for v in synthesis.eliminated}
    assert groups == {"functionality as a TPM (Carricato)", "position of actuators", "number of joints"}


def test_only_ruu_and_ruc_start_with_a_revolute_joint():
    assert [t for t in synthesize().survivors if t.startswith("R")] == ["RUU", "RUC"]


def test_six_dof_synthesis_keeps_the_stewart_legs():
    synthesis = synthesize(6, 6)
    assert synthesis.leg_dof == 6
    assert not synthesis.translational
    assert {"UPS", "SPU", "RUS", "PUS"} <= set(synthesis.survivors)
    # SPS has 7 joint DoF (one idle rod spin): not a candidate of the 6 + 6 (6 - 1) = 36 budget.
    assert "SPS" not in {v.topology for v in synthesis.verdicts}
    verdicts = {v.topology: v for v in synthesis.verdicts}
    assert verdicts["PPPPPP"].eliminated_by.key == "six_dof"


@pytest.mark.parametrize("dof, legs, message", [(3, 2, "do not split evenly"), (3, 1, "five-DoF legs"),
                                                (7, 3, "between 1 and 6")])
def test_synthesis_refuses_impossible_requests(dof, legs, message):
    with pytest.raises(ValueError, match=message):
        synthesize(dof, legs)


def test_topologies_command():
    result = subprocess.run(SYMKIN_CLI + ["topologies", "--dof", "3", "--legs", "3"], capture_output=True,
                            text=True, check=True)
    out = result.stdout
    assert "sum f_i = F + 6 (k - 1) = 15 (eq. 8.4), 5 per leg" in out
    assert "Candidates (Table 8.1, reconstructed): 136 leg topologies" in out
    assert "Eliminated (Table 8.2, reconstructed): 130" in out
    assert "Surviving (6): RUU, RUC, PUU, UPU, CRU, CUR" in out
    assert "RUU, RUC" in out.splitlines()[-1]
    line = next(line for line in out.splitlines() if line.split()[1:2] == ["URU"])
    assert "position of actuators" in line
    data = json.loads(subprocess.run(SYMKIN_CLI + ["topologies", "--json"], capture_output=True, text=True,
                                     check=True).stdout)
    assert len(data["eliminated"]) == 130
    assert data["leg_dof"] == 5
    bad = subprocess.run(SYMKIN_CLI + ["topologies", "--dof", "3", "--legs", "2"], capture_output=True, text=True)
    assert bad.returncode == 1
    assert "do not split evenly" in bad.stderr


def test_mobility_command(tmp_path):
    paths = [str(MODELS_DIR / f"{name}.yaml") for name in ("delta", "stewart", "ur10e")]
    out = subprocess.run(SYMKIN_CLI + ["mobility", *paths], capture_output=True, text=True, check=True).stdout
    assert "F = 6 (8 - 9 - 1) + 15 - 0 + 0 = 3" in out
    assert "F = 6 (14 - 18 - 1) + 36 - 0 + 0 = 6" in out
    assert out.count("as intended") == 3
    assert "P_g = k / F = 3/3 = 1: fully parallel" in out
    # A model whose legs cannot move the platform as intended: exit code 1.
    locked = (MODELS_DIR / "delta.yaml").read_text().replace("  home:", "  mobility: {identical: 1}\n  home:")
    path = tmp_path / "locked.yaml"
    path.write_text(locked)
    result = subprocess.run(SYMKIN_CLI + ["mobility", str(path), "--json"], capture_output=True, text=True)
    assert result.returncode == 1
    assert json.loads(result.stdout)["mobility"] == 2

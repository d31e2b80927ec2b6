"""Issue 33: the base parameters of a classic arm against the published ones - the Staubli RX-90 of Khalil and
Dombre (*Modeling, Identification and Control of Robots*, 2002, the RX-90 of their examples), as SYMORO, the
authors' program, computes them: https://github.com/symoro/symoro, ``Robots/RX90/RX90_regp.txt`` (commit
23db8e59), the table of grouped inertia parameters and the equations before it.

The arm in that file (Khalil and Kleinfinger's modified DH: ^{j-1}T_j = Rx(alpha_j) Tx(d_j) Rz(theta_j)
Tz(r_j); alpha = 0, pi/2, 0, -pi/2, pi/2, -pi/2; d_3 = D3; r_4 = RL4; gravity along z_0; a rotor inertia IA_j
on every joint) has 40 base inertial parameters (the 66 of the table: XX ... M and IA of six links, friction
left out).  Each link's parameters are taken about the origin of its frame j, in its axes: the frames of the
joint chain below, whose joint frame j is Khalil's frame j (Rx(alpha) Tx(d) Tz(r) = Trans(d, -r sin alpha,
r cos alpha) Rx(alpha): the origin ``xyz`` and the roll ``rpy`` of the joint), so that the two sets of
parameters are the same numbers and SYMORO's combinations must span the same space as symkin's K, exactly, for
every D3 and RL4.  The DH table read as written (symkin's joint frame of a modified row is before its Tz(r),
docs/identification.md) has the same count.
"""

from __future__ import annotations

import flint
import sympy

from symkin.derivation import Derivation
from symkin.dynamics.base_parameters import base_parameters
from symkin.dynamics.parameter_names import DISSIPATIVE
from symkin.dynamics.regressor import parameter_names
from symkin.model import model_from_text

#: The RX-90's joints whose joint frames are Khalil's frames (module docstring).
RX90_CHAIN = """name: rx90
parameters:
  D3: {value: 0.45, unit: m, doc: shoulder to elbow (d3 of Khalil's table)}
  RL4: {value: 0.45, unit: m, doc: elbow to wrist centre (r4)}
  G3: 9.81
serial:
  chain:
    - {name: th1, axis: [0, 0, 1]}
    - {name: th2, axis: [0, 0, 1], origin: {rpy: [pi/2, 0, 0]}}
    - {name: th3, axis: [0, 0, 1], origin: {xyz: [D3, 0, 0]}}
    - {name: th4, axis: [0, 0, 1], origin: {xyz: [0, RL4, 0], rpy: [-pi/2, 0, 0]}}
    - {name: th5, axis: [0, 0, 1], origin: {rpy: [pi/2, 0, 0]}}
    - {name: th6, axis: [0, 0, 1], origin: {rpy: [-pi/2, 0, 0]}}
gravity: [0, 0, G3]
"""

#: The same arm as the DH table of RX90_regp.txt (row j: alpha_j, d_j as a, r_j as d).
RX90_DH = """name: rx90_dh
parameters:
  D3: 0.45
  RL4: 0.45
  G3: 9.81
serial:
  dh:
    convention: modified
    rows:
      - {name: th1, alpha: 0, a: 0, d: 0, theta: 0}
      - {name: th2, alpha: pi/2, a: 0, d: 0, theta: 0}
      - {name: th3, alpha: 0, a: D3, d: 0, theta: 0}
      - {name: th4, alpha: -pi/2, a: 0, d: RL4, theta: 0}
      - {name: th5, alpha: pi/2, a: 0, d: 0, theta: 0}
      - {name: th6, alpha: -pi/2, a: 0, d: 0, theta: 0}
gravity: [0, 0, G3]
"""

#: SYMORO's names of a link's parameters and symkin's.
SYMORO_NAMES = {"XX": "Ixx", "XY": "Ixy", "XZ": "Ixz", "YY": "Iyy", "YZ": "Iyz", "ZZ": "Izz", "MX": "mx", "MY": "my",
                "MZ": "mz", "M": "m"}


def _symoro_base_parameters() -> list[sympy.Expr]:
    """The 40 grouped parameters of RX90_regp.txt as linear forms in SYMORO's symbols (XX1, ..., IA6), its
    equations transcribed in their order."""
    s = {f"{name}{j}": sympy.Symbol(f"{name}{j}") for name in (*SYMORO_NAMES, "IA") for j in range(1, 7)}
    D3, RL4 = sympy.symbols("D3 RL4")
    XXR6 = s["XX6"] - s["YY6"]
    MR5 = s["M5"] + s["M6"]
    XXR5 = s["XX5"] - s["YY5"] + s["YY6"]
    ZZR5 = s["YY6"] + s["ZZ5"]
    MYR5 = s["MY5"] + s["MZ6"]
    LamMS134, LamM14 = 2 * RL4, RL4 ** 2
    MR4 = s["M4"] + MR5
    XXR4 = s["XX4"] - s["YY4"] + s["YY5"]
    ZZR4 = s["YY5"] + s["ZZ4"]
    MYR4 = s["MY4"] - s["MZ5"]
    LamM43 = D3 ** 2
    MR3 = s["M3"] + MR4
    XXR3 = LamM14 * MR4 + LamMS134 * s["MZ4"] + s["XX3"] - s["YY3"] + s["YY4"]
    ZZR3 = LamM14 * MR4 + LamMS134 * s["MZ4"] + s["YY4"] + s["ZZ3"]
    MYR3 = MR4 * RL4 + s["MY3"] + s["MZ4"]
    YYR2 = LamM43 * MR3 + s["YY2"] + s["YY3"]
    XXR2 = s["XX2"] + s["YY3"] - YYR2
    XZR2 = -D3 * s["MZ3"] + s["XZ2"]
    ZZR2 = s["IA2"] + LamM43 * MR3 + s["ZZ2"]
    MXR2 = D3 * MR3 + s["MX2"]
    ZZR1 = s["IA1"] + YYR2 + s["ZZ1"]
    table = [ZZR1, XXR2, s["XY2"], XZR2, s["YZ2"], ZZR2, MXR2, s["MY2"]]  # rows 1 and 2 of the grouped table
    for j, (XXR, ZZR, MY) in zip(range(3, 7), ((XXR3, ZZR3, MYR3), (XXR4, ZZR4, MYR4), (XXR5, ZZR5, MYR5),
                                                (XXR6, s["ZZ6"], s["MY6"]))):
        table += [XXR, s[f"XY{j}"], s[f"XZ{j}"], s[f"YZ{j}"], ZZR, s[f"MX{j}"], MY, s[f"IA{j}"]]
    return table


def _inertial_base_parameters(text: str):
    """symkin's base parameters of the model's inertial parameters and rotor inertias (friction left out)."""
    model = model_from_text(text, "rx90")
    names = parameter_names(model)
    kept = [k for k, name in enumerate(names) if name.rsplit(".", 1)[1] not in DISSIPATIVE]
    rows = [[row[k] for k in kept] for row in Derivation(model)["regressor_graph"]]
    return base_parameters(model, rows, [names[k] for k in kept])


def _symoro_symbol(name: str) -> sympy.Symbol:
    """SYMORO's symbol of symkin's parameter: link<j>.<p> -> <P><j>, th<j>.Ia -> IA<j>."""
    owner, parameter = name.split(".")
    if parameter == "Ia":
        return sympy.Symbol(f"IA{owner.removeprefix('th')}")
    return sympy.Symbol({v: k for k, v in SYMORO_NAMES.items()}[parameter] + owner.removeprefix("link"))


def _rank(rows: list[list[sympy.Expr]], point: dict[sympy.Symbol, sympy.Rational]) -> int:
    return flint.fmpq_mat([[flint.fmpq(int(v.p), int(v.q)) for v in (sympy.Rational(e.xreplace(point))
                                                                      for e in row)] for row in rows]).rank()


def test_the_rx90_has_khalils_40_base_inertial_parameters_and_his_regrouping():
    """The count is SYMORO's 40, and every grouped parameter of SYMORO is a combination of symkin's base
    parameters for every D3 and RL4 (SYMORO's form s equals sum_b s_b pi_b with s_b its coefficients on the base
    columns, symbolically), the 40 forms independent: the two sets span the same space."""
    found = _inertial_base_parameters(RX90_CHAIN)
    assert len(found.base) == 40
    assert set(found.geometry) == {"D3", "RL4"}
    symbols = [_symoro_symbol(name) for name in found.names]
    K = sympy.Matrix(found.combinations)
    assert K[:, list(found.base)] == sympy.eye(40)
    published = sympy.Matrix([[sympy.expand(form).coeff(symbol) for symbol in symbols]
                              for form in _symoro_base_parameters()])
    assert all(e.is_polynomial(*sympy.symbols("D3 RL4")) for e in published)
    difference = (published - published[:, list(found.base)] * K).applyfunc(sympy.cancel)
    assert difference == sympy.zeros(40, len(found.names))
    point = {sympy.Symbol("D3"): sympy.Rational(9, 20), sympy.Symbol("RL4"): sympy.Rational(7, 16)}
    assert _rank(published.tolist(), point) == 40


def test_the_rx90_read_from_its_dh_table_has_40_too():
    """The count does not depend on where along its axis a link's frame is: the DH table as written (each link's
    parameters about the joint frame before Tz(r_j)) has 40 as well."""
    assert len(_inertial_base_parameters(RX90_DH).base) == 40

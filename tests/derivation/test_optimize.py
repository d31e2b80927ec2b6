"""Parameter folding never costs operations; the combined scene function shares one CSE."""

from __future__ import annotations

import numpy as np
import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

import re

from conftest import GENERATED_DIR, random_inputs, random_q
from symkin import pipeline
from symkin.derivation import emitted_quantities
from symkin.errors import DerivationError
from symkin.ir.spec import ColumnMap, FunctionSpec, InputSpec, OptimizedFunction, OutputSpec, map_targets
from symkin.optimize import fold_parameters, optimize
from symkin.optimize.schedule import peak_live
from symkin.ir.opcount import op_count
from tolerances import CLOSED_FORM, DYNAMICS, KINEMATICS

X = sympy.symbols("x0:3", real=True)
P = sympy.symbols("p0:3", real=True)
VALUES = st.sampled_from([sympy.Integer(0), sympy.Integer(1), sympy.Integer(-1), sympy.Integer(2),
                          sympy.Rational(1807, 10000), sympy.Rational(-6127, 10000), sympy.pi / 2,
                          sympy.sqrt(2) / 2, sympy.Rational(1, 3)])


def _expressions():
    leaves = st.sampled_from(X + P) | st.sampled_from([sympy.Integer(2), sympy.Rational(1, 2), sympy.pi])

    def extend(children):
        return (st.builds(lambda a, b: a + b, children, children)
                | st.builds(lambda a, b: a * b, children, children)
                | st.builds(lambda a, b: a - b, children, children)
                | st.builds(lambda a, b: a / (b**2 + 1), children, children)
                | st.builds(lambda a, n: a ** n, children, st.sampled_from([2, 3, -1, sympy.Rational(1, 2)]))
                | st.builds(sympy.sin, children) | st.builds(sympy.cos, children)
                | st.builds(sympy.atan2, children, children))

    return st.recursive(leaves, extend, max_leaves=8)


def _spec(exprs) -> FunctionSpec:
    vector = InputSpec("q", "vector", X, tuple(map(str, X)), ("rad",) * 3, "coordinates")
    params = tuple(InputSpec(str(p), "parameter", (p,), (str(p),), ("",), "parameter", sympy.Integer(1)) for p in P)
    return FunctionSpec("f", "f", "f", (vector,) + params,
                        (OutputSpec("y", sympy.ImmutableMatrix(exprs), "output", shape=(len(exprs),)),))


@settings(max_examples=300, deadline=None)
@given(st.lists(_expressions(), min_size=1, max_size=4), st.lists(VALUES, min_size=3, max_size=3))
def test_folding_never_increases_the_op_count(exprs, values):
    spec = _spec(exprs)
    spec = FunctionSpec(spec.name, spec.summary, spec.doc,
                        spec.inputs[:1] + tuple(InputSpec(i.name, i.kind, i.symbols, i.element_names, i.units, i.doc, v)
                                                for i, v in zip(spec.inputs[1:], values)), spec.outputs)
    try:
        folded = fold_parameters(spec, [str(p) for p in P])
    except DerivationError as error:  # a value that divides by zero: refused, named
        assert "make an output undefined" in str(error)
        return
    before = op_count(e for o in spec.outputs for e in o.entries)
    after = op_count(e for o in folded.outputs for e in o.entries)
    assert after <= before, (exprs, values)


def test_folding_a_value_that_divides_by_zero_is_a_named_error():
    x, p0 = X[0], P[0]
    for expr in (sympy.atan2(0, 1 / p0), x / p0):
        spec = _spec([expr])
        spec = FunctionSpec(spec.name, spec.summary, spec.doc,
                            spec.inputs[:1] + tuple(InputSpec(i.name, i.kind, i.symbols, i.element_names, i.units,
                                                              i.doc, sympy.Integer(0)) for i in spec.inputs[1:]),
                            spec.outputs)
        with pytest.raises(DerivationError, match="make an output undefined"):
            fold_parameters(spec, [str(p0)])


def test_op_count_model():
    x, y = X[:2]
    assert op_count([x + y + 2 + sympy.pi]) == 2          # constant terms are one literal
    assert op_count([sympy.sqrt(2) * sympy.pi * x]) == 1  # constant factors are one literal
    assert op_count([-x * y]) == 1
    assert op_count([x**3 / y]) == 3                      # x*x*x/y
    assert op_count([1 / (x * y**2)]) == 3                # 1.0/(x*y*y)
    assert op_count([2 * x / sympy.sqrt(y)]) == 3         # 2.0*x/sqrt(y)
    assert op_count([y**-2]) == 2                         # 1.0/(y*y)
    assert op_count([sympy.cos(sympy.Rational(1, 10)) + x]) == 1
    assert op_count([sympy.sin(x) ** 2]) == 2


def fold_all(model, derivation, name):
    """(optimized with every parameter free, optimized with every parameter folded) for one quantity.

    The dynamics tests use it as ``free, folded = fold_all(models["ur10e"], derivations["ur10e"], "M")``.
    """
    spec = derivation[name]
    return optimize(spec), optimize(spec, tuple(p.name for p in model.parameters))


@pytest.mark.parametrize("name", ["ur10e", "planar_2r"])
def test_folding_all_parameters_never_costs_and_keeps_the_values(name, models, derivations):
    model = models[name]
    quantities = derivations[name].available(emitted_quantities())[0]
    assert {"fk", "jacobian", "mass_matrix"} <= set(quantities)
    for quantity in quantities:
        spec = derivations[name][quantity]
        free, folded = fold_all(model, derivations[name], quantity)
        assert not folded.spec.parameter_inputs
        if spec.parameter_inputs:
            assert folded.op_counts["folded"] <= folded.op_counts["derived"], quantity
        assert folded.op_counts["cse"] <= free.op_counts["cse"], quantity
        inputs = random_inputs(model, spec, np.random.default_rng(8), 8)
        vectors = [list(i.symbols) for i in spec.vector_inputs]
        defaults = {p.symbols[0]: p.default for p in spec.parameter_inputs}
        got, want = _evaluate(folded, vectors, {}), _evaluate(free, vectors, defaults)
        for point in zip(*inputs):
            expected = want(*point)
            scale = max(1.0, float(np.max(np.abs(expected), initial=0.0)))
            np.testing.assert_allclose(got(*point), expected, rtol=0, atol=DYNAMICS * scale,
                                       err_msg=f"{quantity} at {point}")


def test_folding_the_ur10e_lengths_reduces_its_mass_matrix(models, derivations):
    """Products of DH lengths (a2*a3, d5**2...) become single literals once the lengths are numbers."""
    free, folded = fold_all(models["ur10e"], derivations["ur10e"], "mass_matrix")
    assert folded.op_counts["cse"] < free.op_counts["cse"], (folded.op_counts, free.op_counts)


def test_folding_shrinks_products_of_parameters(tmp_path):
    """A link length written as a product of parameters folds into one number."""
    from symkin.derivation import Derivation
    from symkin.model import load_model

    path = tmp_path / "arm.yaml"
    path.write_text("name: arm\nparameters:\n  l: 0.5\n  k: 3\n  s: 0.25\n"
                    "serial:\n  dh:\n    convention: classic\n    rows:\n"
                    "      - [t1, R, 0, 0, k*l*s, 0]\n      - [t2, R, 0, 0, l/k, 0]\n"
                    "task_space: [x, y]\n")
    model = load_model(path)
    free, folded = fold_all(model, Derivation(model), "fk")
    assert folded.op_counts["folded"] < folded.op_counts["derived"]
    assert folded.op_counts["cse"] < free.op_counts["cse"]


def _evaluate(f, vectors, values):
    """Every output entry of an optimized function, its CSE temporaries evaluated in order."""
    temporaries = [(symbol, expr.xreplace(values)) for symbol, expr in f.temporaries]
    entries = [e.xreplace(values) for output in f.outputs for e in output]
    fn = sympy.lambdify(vectors, entries, modules="numpy", cse=lambda exprs: (temporaries, exprs))
    return lambda *point: np.array(fn(*point), dtype=float)


def test_combined_function_shares_one_cse_and_is_recorded(models):
    model = models["ur10e"]
    request = pipeline.resolve_request(model, "fk,frames,jacobian,jacobian_geometric", "numpy",
                                       combine="fk,jacobian,jacobian_geometric")
    result = pipeline.generate(model, request)
    records = {f["name"]: f for f in result.manifest["functions"]}
    scene = records[pipeline.COMBINED_FUNCTION]
    assert scene["combines"] == ["fk", "jacobian", "jacobian_geometric"]
    parts = [records[name] for name in scene["combines"]]
    assert scene["op_counts"]["cse"] < sum(p["op_counts"]["cse"] for p in parts)
    assert scene["op_counts"]["derived"] == sum(p["op_counts"]["derived"] for p in parts)
    names = [o["name"] for o in scene["outputs"]]
    assert names[0] == "base_T_tcp"
    assert "jacobian_J" in names
    assert "jacobian_geometric_J" in names
    assert len(set(names)) == len(names)
    assert [i["name"] for i in scene["inputs"]] == ["q", "d1", "a2", "a3", "d4", "d5", "d6"]


def test_single_output_scene_has_no_combined_function(models):
    model = models["planar_2r"]
    result = pipeline.generate(model, pipeline.resolve_request(model, "fk", "numpy"))
    assert [f["name"] for f in result.manifest["functions"]] == ["fk"]


def test_folded_functions_agree_across_backends(models, tmp_path):
    """--fixed all: parameters vanish from every backend's signatures, values stay the model's."""
    from symkin import load

    model = models["planar_2r"]
    request = pipeline.resolve_request(model, "fk,jacobian", "numpy,c,casadi", "all")
    target = pipeline.write(pipeline.generate(model, request), tmp_path)
    q = random_q(model, np.random.default_rng(4), 10)
    reference = load(target).fk(q)
    for backend in ("c", "casadi"):
        folded = load(target, backend=backend)
        with pytest.raises(TypeError):
            folded.fk(q, l1=0.2)
        np.testing.assert_allclose(folded.fk(q), reference, rtol=0, atol=CLOSED_FORM)  # the planar FK, reach < 1 m


def test_angle_sums_are_expanded_to_one_sin_cos_pair_per_angle(derivations):
    from symkin.optimize import expand_trig_sums

    q1, q2, q3 = X
    spec = _spec([sympy.sin(q1 + q2 + q3), sympy.cos(q1 + q2), sympy.sin(2 * q3 - q1), sympy.cos(q2 + sympy.pi / 3),
                  sympy.sin(q1)])
    expanded = expand_trig_sums(spec)
    calls = {e for e in expanded.outputs[0].expr.atoms(sympy.sin, sympy.cos)}
    assert calls == {f(q) for f in (sympy.sin, sympy.cos) for q in (q1, q2, q3)}
    point = {q1: 0.3, q2: -1.2, q3: 2.5}
    for got, want in zip(expanded.outputs[0].entries, spec.outputs[0].entries):
        # products of <= 3 sines and cosines (<= 1) summed over <= 4 terms, in 53-bit Floats: KINEMATICS
        assert abs(float(got.subs(point)) - float(want.subs(point))) <= KINEMATICS
    # In the optimized UR10e functions every trigonometric call takes a single joint angle.
    optimized = optimize(derivations["ur10e"]["jacobian"])
    arguments = {call.args[0] for _, e in optimized.temporaries for call in e.atoms(sympy.sin, sympy.cos)}
    assert arguments
    assert all(a.is_Symbol for a in arguments)


def _in_cse_order(function: OptimizedFunction) -> OptimizedFunction:
    """``function`` with its temporaries back in CSE's order: their names number it (``_x0``, ``_x1``...)."""
    order = sorted(function.temporaries, key=lambda t: int(str(t[0]).removeprefix("_x")))
    return OptimizedFunction(function.spec, tuple(order), function.outputs, function.op_counts)


@pytest.mark.parametrize("quantity", ["inverse_dynamics_derivatives", "forward_dynamics_derivatives", "mass_matrix"])
def test_the_temporaries_come_in_the_order_the_outputs_need_them(quantity, models, derivations):
    """symkin.optimize.schedule: each temporary after those it uses, never more values live at once than in CSE's
    order (the UR10e's inverse-dynamics derivatives, parameters free: 211 against 321), and the generated C stores
    each output entry right after the temporary it needs last (every parameter folded, as generated/ holds it); the
    numpy module too, deleting each temporary after its last use (never one used after it is deleted), so that it
    holds few of them at once."""
    optimized = optimize(derivations["ur10e"][quantity])
    computed: set[sympy.Symbol] = set()
    temporaries = {symbol for symbol, _ in optimized.temporaries}
    for symbol, value in optimized.temporaries:
        assert value.free_symbols & temporaries <= computed, symbol
        computed.add(symbol)
    assert peak_live(optimized) <= peak_live(_in_cse_order(optimized))
    if quantity == "inverse_dynamics_derivatives":
        assert peak_live(optimized) < 0.7 * peak_live(_in_cse_order(optimized))
    source = (GENERATED_DIR / "ur10e" / "ur10e.c").read_text()
    body = source[source.index(f"void ur10e_{quantity}("):]
    body = body[:body.index("\n}\n")]
    last = None                                    # the temporary defined last, before a run of stores
    stores = 0
    for line in body.splitlines():
        definition = re.match(r"\s+const double (_x\d+) = ", line)
        if definition:
            last = definition.group(1)
        elif re.match(r"\s+\w+\[\d+\] = ", line):
            stores += 1
            used = set(re.findall(r"_x\d+", line.split("=", 1)[1]))
            assert (last in used) if last else not used, line
    assert stores == sum(len(output) for output in optimized.outputs)
    # the numpy module stores entries as soon as it can too, and deletes each temporary after its last use
    source = (GENERATED_DIR / "ur10e" / "ur10e.py").read_text()
    body = source[source.index(f"def {quantity}("):]
    body = body[body.index("\n    batch = "):body.index("\n    return ")]          # the function's own return
    live: set[str] = set()
    held = 0                                       # the most temporaries held at once
    for line in body.splitlines():
        deleted = re.match(r"\s+del (.*)", line)
        if deleted:
            names = set(deleted.group(1).split(", "))
            assert names <= live, line
            live -= names
            continue
        target, _, value = line.partition(" = ")
        assert set(re.findall(r"_x\d+", value)) <= live, line
        if re.fullmatch(r"\s+_x\d+", target):
            live.add(target.strip())
            held = max(held, len(live))
    assert not live
    assert held >= 1
    if quantity == "inverse_dynamics_derivatives":
        assert held < 0.4 * len(optimized.temporaries)


def test_a_column_map_unrolls_into_temporaries_its_numbers_folded():
    """A spec's column map (symkin.optimize.maps): its shared value and columns share the CSE, its columns are
    unrolled into one run of temporaries (a MapBlock), a column of numbers folds into its copy, and the result
    equals the spec's own expansion; the C backend prints the run as one loop (the UR10e's forward-dynamics
    derivatives: the LDL^T substitutions' body once for the 3n = 18 columns)."""
    x0, x1, x2 = X
    s0, b0, b1, u0 = (sympy.Symbol(name, real=True) for name in ("_s0", "_b0", "_b1", "_u0"))
    targets = map_targets(0, 3, 2)
    column_map = ColumnMap(((s0, x0 * x1),), (b0, b1), ((u0, b0 * s0 + b1),), (u0, u0 * b1),
                           ((x2, sympy.sin(x1)), (sympy.Integer(1), sympy.Integer(0)), (sympy.Integer(0), x0)), targets)
    vector = InputSpec("q", "vector", X, tuple(map(str, X)), ("rad",) * 3, "coordinates")
    entries = [t for column in targets for t in column]
    spec = FunctionSpec("f", "f", "f", (vector,), (OutputSpec("y", sympy.ImmutableMatrix(entries), "y", shape=(6,)),),
                        maps=(column_map,))
    f = optimize(spec)
    (block,) = f.maps
    before = dict(f.temporaries[:block.start])
    assert before[block.targets[1][0]] == x0 * x1   # the column (1, 0): u0 = s0 (the shared value) and u0 * b1 = 0
    assert block.targets[1][1] == 0
    assert block.stop - block.start == 3            # u0 and u0 * b1 of the first column, u0 of the last
    point = (0.3, -1.2, 0.7)
    expected = np.array([float(e.subs(dict(zip(X, point)))) for e in spec.expanded_outputs()[0]])
    np.testing.assert_allclose(_evaluate(f, [X], {})(point), expected, rtol=CLOSED_FORM)
    body = (GENERATED_DIR / "ur10e" / "ur10e.c").read_text()
    body = body[body.index("void ur10e_forward_dynamics_derivatives("):]
    body = body[:body.index("\n}\n")]
    assert body.count("for (int _c = 0; _c < 18; ++_c)") == 1
    n = 6  # the body: n forward substitutions less the first (b_0 itself), n back ones
    assert len(re.findall(r"const double _u\d+ = ", body)) == 2 * n - 1

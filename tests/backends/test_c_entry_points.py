"""Issue 34: the compiled CPython entry points of the C backend (symkin.backends.c.loader_entry_points).

References: the ctypes binding of the same library (SYMKIN_C_ENTRY=ctypes), whose values the other tests
check against the numpy backend and the references: the compiled functions return the same bits for every
example model and every function, one configuration at a time (ndarray, list, out=); every other kind of
call (wrong shapes, dtypes, layouts, batches, keywords, bad out=) either gives the ctypes function's result
or raises its exception with its message, or a clear ValueError for a bad out=, and never crashes.
"""

from __future__ import annotations

import inspect
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import GENERATED_DIR
from symkin.backends.c import loader_entry_points
from symkin.runtime.loader import load

EXAMPLES = sorted(p.name for p in GENERATED_DIR.iterdir() if (p / "manifest.json").exists())


@pytest.fixture(autouse=True)
def compiled_entry_points(monkeypatch):
    """The suite loads the ctypes functions (conftest: test time); here the C backend's own default."""
    monkeypatch.delenv(loader_entry_points.ENTRY_VARIABLE, raising=False)


@pytest.fixture(scope="module", params=EXAMPLES)
def pair(request):
    """(compiled, ctypes) bindings of one example model."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(loader_entry_points.ENTRY_VARIABLE, "ctypes")
        plain = load(GENERATED_DIR / request.param, "c")
        patch.delenv(loader_entry_points.ENTRY_VARIABLE)
        compiled = load(GENERATED_DIR / request.param, "c")
    return compiled, plain


def _inputs(record, rng, batch=()):
    return [rng.uniform(-1.5, 1.5, batch + (int(i["shape"][0]),)) for i in record["inputs"] if i["kind"] != "parameter"]


def _same(a, b) -> bool:
    if isinstance(a, tuple):
        return (type(a).__name__ == type(b).__name__ and a._fields == b._fields      # each binding has its class
                and all(_same(x, y) for x, y in zip(a, b)))
    return type(a) is np.ndarray and a.dtype == np.float64 and np.array_equal(a, b, equal_nan=True)


def test_every_function_is_compiled_and_returns_the_ctypes_bits(pair):
    compiled, plain = pair
    rng = np.random.default_rng(34)
    for record in compiled.manifest["functions"]:
        name = record["name"]
        fast, slow = getattr(compiled, name), getattr(plain, name)
        assert type(fast).__name__ == "builtin_function_or_method", name
        reference = inspect.signature(slow)                         # the numpy backend's (test_backends_agree)
        out = inspect.Parameter("out", inspect.Parameter.KEYWORD_ONLY, default=None)
        assert inspect.signature(fast) == reference.replace(parameters=[*reference.parameters.values(), out]), name
        assert fast.__doc__.startswith(slow.__doc__.splitlines()[0]), name
        for _ in range(3):
            args = _inputs(record, rng)
            expected = slow(*args)
            assert _same(fast(*args), expected), name
            assert _same(fast(*[a.tolist() for a in args]), expected), name      # sequences of floats
            out = (np.empty_like(expected) if isinstance(expected, np.ndarray)
                   else tuple(np.empty_like(e) for e in expected))
            written = fast(*args, out=out)
            assert _same(written, expected), name
            assert (written is out) if isinstance(out, np.ndarray) else all(w is o for w, o in zip(written, out))
        parameters = [i for i in record["inputs"] if i["kind"] == "parameter"]
        if parameters:
            args = _inputs(record, rng)
            changed = {p["name"]: float(p["default"]) * 1.1 + 0.01 for p in parameters}
            assert _same(fast(*args, **changed), slow(*args, **changed)), name
        batch = _inputs(record, rng, (4,))
        assert _same(fast(*batch), slow(*batch)), name                             # a batch: the fallback


def _outcome(function, *args, **kwargs):
    try:
        return "value", function(*args, **kwargs)
    except (ValueError, TypeError, OverflowError) as err:
        return type(err).__name__, str(err)


def _same_outcome(a, b) -> bool:
    if a[0] != b[0]:
        return False
    return _same(a[1], b[1]) if a[0] == "value" else a[1] == b[1]


@pytest.mark.parametrize("model", ["ur10e"])
def test_any_other_call_behaves_as_the_ctypes_function_and_never_crashes(model):
    compiled = load(GENERATED_DIR / model, "c")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(loader_entry_points.ENTRY_VARIABLE, "ctypes")
        plain = load(GENERATED_DIR / model, "c")
    rng = np.random.default_rng(7)
    q = rng.uniform(-1, 1, 6)
    wide = rng.uniform(-1, 1, 12)
    calls = {
        "short": ((q[:5],), {}), "column": ((q[:, None],), {}), "float32": ((q.astype(np.float32),), {}),
        "int": ((np.arange(6),), {}), "strided": ((wide[::2],), {}), "fortran batch": ((np.asfortranarray(
            rng.uniform(-1, 1, (3, 6))),), {}), "byte-swapped": ((q.astype(">f8"),), {}),
        "short list": (([0.1] * 5,), {}), "list of text": ((["0.1"] * 6,), {}), "nested list": (([[0.1] * 6],), {}),
        "None": ((None,), {}), "keyword q": ((), {"q": q}), "no argument": ((), {}), "two arguments": ((q, q), {}),
        "unknown keyword": ((q,), {"l9": 1.0}), "numpy scalar parameter": ((q,), {"d1": np.float64(0.2)}),
        "array parameter": ((q,), {"d1": np.array([0.1, 0.2])}), "bool parameter": ((q,), {"d1": True}),
        "huge int parameter": ((q,), {"d1": 10 ** 400}), "text parameter": ((q,), {"d1": "0.1"}),
        "repeated keyword": ((q,), {"q": q}), "subclass": ((np.ma.masked_array(q),), {}),
    }
    for label, (args, kwargs) in calls.items():
        assert _same_outcome(_outcome(compiled.fk, *args, **kwargs), _outcome(plain.fk, *args, **kwargs)), label
    expected = plain.fk(q)
    bad_outs = {"wrong shape": np.empty((4, 3)), "float32": np.empty((4, 4), np.float32),
                "Fortran": np.asfortranarray(np.empty((4, 4)))[:, ::-1], "read-only": np.empty((4, 4)),
                "list": [[0.0] * 4] * 4, "tuple for one output": (np.empty((4, 4)),)}
    bad_outs["read-only"].flags.writeable = False
    for label, out in bad_outs.items():
        try:
            compiled.fk(q, out=out)
        except ValueError as err:
            assert "fk(): out= must be a writeable float64 C-contiguous array" in str(err), label
        else:
            pytest.fail(f"out= {label} was accepted")
    batch = rng.uniform(-1, 1, (5, 6))
    out = np.empty((5, 4, 4))
    assert compiled.fk(batch, out=out) is out                                        # a batch into out=: a copy
    assert np.array_equal(out, plain.fk(batch))
    with pytest.raises(ValueError, match="out= must be a tuple of 5"):
        compiled.combined(q, q, out=np.empty((4, 4)))
    assert np.array_equal(compiled.fk(q, out=None), expected)


def test_calls_hold_no_references():
    """No reference leaks: the inputs' and out='s reference counts are unchanged after many calls."""
    compiled = load(GENERATED_DIR / "ur10e", "c")
    q, qd = np.linspace(0.1, 0.6, 6), np.linspace(-0.3, 0.2, 6)
    out = tuple(np.empty(shape) for shape in ((4, 4), (6, 6), (6, 6), (6,), (6,)))
    before = [sys.getrefcount(x) for x in (q, qd, *out)]
    for _ in range(1000):
        compiled.combined(q, qd)
        compiled.combined(q, qd, out=out)
        compiled.fk(q, out=out[0])
        compiled.fk(q[None, :])
    assert [sys.getrefcount(x) for x in (q, qd, *out)] == before


def test_text_from_the_model_cannot_leave_the_c_string():
    hostile = 'a"b\\c??=d\n*/ #include <stdio.h>\x00é'
    literal = loader_entry_points.c_string(hostile)
    body = literal[1:-1]
    assert '"' not in body.replace('\\042', '')
    assert all(32 <= ord(c) < 127 for c in literal)
    assert "??" not in literal
    assert loader_entry_points.c_double(0.1) == "0x1.999999999999ap-4"


def test_a_cached_extension_loads_without_sympy_or_jinja2_and_cache_list_names_its_model(tmp_path):
    env = {**os.environ, "SYMKIN_CACHE_DIR": str(tmp_path / "cache")}
    code = ("import sys, numpy as np; from symkin import load; "
            f"m = load({str(GENERATED_DIR / 'planar_2r')!r}, backend='c'); m.fk(np.zeros(2)); "
            "print(type(m.fk).__name__, 'sympy' in sys.modules, 'jinja2' in sys.modules)")
    first = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert "compiling the CPython entry points of planar_2r" in first.stderr
    again = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert again.stdout.split() == ["builtin_function_or_method", "False", "False"]
    assert again.stderr == ""
    listing = subprocess.run([sys.executable, "-m", "symkin", "cache", "list"], capture_output=True, text=True,
                             env=env, check=True).stdout
    assert listing.count(" planar_2r ") == 2                     # the library and its entry points

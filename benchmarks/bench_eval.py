"""Evaluation speed of UR10e code: symkin's numpy, C and CasADi backends beside Pinocchio and SymForce.

Run with ``make bench`` or ``python benchmarks/bench_eval.py [--batch N] [--calls N] [--cflags FLAGS]``.

Cases (functions generated with every parameter folded, as in a fixed-geometry servo loop):

* ``FK``     base_T_tcp;
* ``FK+J``   base_T_tcp and the geometric Jacobian, the combined function of one shared CSE;
* ``M``, ``M+V+G`` when the dynamics quantities are registered (found by their output
  names M, V, G), likewise;
* ``dtau``   d tau/dq, d tau/dqd and d tau/dqdd = M (``inverse_dynamics_derivatives``, issue 65);
* ``dqdd``   d qdd/dq, d qdd/dqd and d qdd/dtau = M^-1 (``forward_dynamics_derivatives``).

Columns:

* ``py call``   microseconds per call from Python, one configuration (best of 9 runs of at least 0.1 s
  each, the implementations of a case in turn: :func:`interleaved_best_us`); ``symkin c`` is the compiled
  CPython entry point, ``symkin c (ctypes)`` the same library through ctypes (SYMKIN_C_ENTRY=ctypes); a last
  table sets them beside the compiled entry writing into arrays the caller allocated once (``out=``, as a control
  loop calls it and as Pinocchio's binding writes into its ``Data``), Pinocchio's binding and the floor: an empty
  call of a CPython builtin (``id``) in the same loop plus the C time;
* ``py batch``  nanoseconds per configuration of one batched call over ``--batch`` configurations
  (numpy and C: the generated vectorized functions; CasADi: ``Function.map``; Pinocchio: a
  Python loop, as a Python user would write it);
* ``C call``    nanoseconds per call of the single-configuration C function, timed in C by a
  harness this script compiles (best of 5 runs of ``--calls`` calls over 1024 configurations);
* ``C batch``   nanoseconds per configuration of the C batch entry point, timed in C.

A line gives each case's single-configuration C function's machine code in bytes (its symbol's size in ``nm -S`` of
the harness: the sincos helper, where GCC keeps it apart, is not counted) beside the CPU's L1 instruction cache: code
that does not fit it with its caller's is fetched from L2 at every call.  The next line shows it: each single call
timed alone, with a function of about 13 KB of other code (:func:`other_code_c`) called after it in the same loop,
and the two apart, summed.

Pinocchio: ``computeFrameJacobian`` (which also updates the TCP placement) for FK+J,
``forwardKinematics`` + ``updateFramePlacement`` for FK, ``crba`` for M, ``crba`` + ``rnea``
(zero acceleration: V + G) + ``computeGeneralizedGravity`` for M+V+G, ``computeRNEADerivatives`` (its analytical
derivatives, Carpentier and Mansard 2018, which give M as d tau/dqdd too) for dtau, ``computeABADerivatives`` (M^-1
too) for dqdd.  SymForce (when it
and the Eigen headers are installed): C++ generated from sf.Pose3 compositions of the same
joints and ``pose.jacobian(q)`` (FK+J only), timed in C++ by the same harness loop.
Targets of issue 4: C call M <= 250 ns, FK+J <= 150 ns; C batch M+V+G <= 150 ns/config;
numpy batch <= 1 us/config; of issue 65: dtau from Python <= 0.6 us and >= 6x faster than Pinocchio's binding,
C batch <= 150 ns/config, dqdd from Python <= 1.0 us.
"""

from __future__ import annotations

import argparse
import functools
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT.parent))
sys.path.insert(0, str(ROOT))

from competitors import pinocchio_model, symforce_fk_jacobian_codegen  # noqa: E402
from symkin import load, pipeline  # noqa: E402
from symkin.text_table import format_table  # noqa: E402
from symkin.derivation import Derivation, emitted_quantities  # noqa: E402
from symkin.errors import DerivationError  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.backends.c.loader_entry_points import ENTRY_VARIABLE  # noqa: E402

MODEL = ROOT.parent / "models" / "ur10e.yaml"
#: The C flags of a servo loop's build on its own machine (docs/generated-code.md): its instruction set, and fused
#: multiply-adds - one rounding per multiply-add instead of two, what GCC does by default outside ISO C mode and
#: clang within an expression; symkin's C is ISO C99, whose default keeps them apart.  The test suite's second pass
#: (tests/conftest.py, Makefile FOREIGN_ARITHMETIC) checks the generated C's error bounds built this way.
SERVO_CFLAGS = "-O3 -march=native -ffp-contract=fast"
RING = 1024  # configurations cycled through by the single-call timings


def find_cases(model) -> dict[str, list[str]]:
    """{case name: quantities} for the cases this symkin can derive."""
    derivation = Derivation(model)
    by_output: dict[str, str] = {}
    for name in emitted_quantities():
        try:
            spec = derivation[name]
        except DerivationError:
            continue
        outputs = [o.name for o in spec.outputs]
        if len(outputs) == 1:
            by_output.setdefault(outputs[0], name)
    cases = {"FK": ["fk"], "FK+J": ["fk", "jacobian_geometric"]}
    if "M" in by_output:
        cases["M"] = [by_output["M"]]
        if "V" in by_output and "G" in by_output:
            cases["M+V+G"] = [by_output["M"], by_output["V"], by_output["G"]]
    if "inverse_dynamics_derivatives" in emitted_quantities():
        cases["dtau"] = ["inverse_dynamics_derivatives"]
        cases["dqdd"] = ["forward_dynamics_derivatives"]
    return cases


def generate(model, quantities: list[str], out: Path) -> Path:
    combine = quantities if len(quantities) > 1 else "none"
    request = pipeline.resolve_request(model, quantities, ["numpy", "c", "casadi"], "all", combine=combine)
    return pipeline.write(pipeline.generate(model, request), out)


def function_name(quantities: list[str]) -> str:
    return quantities[0] if len(quantities) == 1 else pipeline.COMBINED_FUNCTION


def random_inputs(record: dict, n: int, rng: np.random.Generator) -> list[np.ndarray]:
    return [rng.uniform(-np.pi, np.pi, (n, i["shape"][0])) for i in record["inputs"] if i["kind"] == "vector"]


#: A timed run of Python calls lasts at least this long (s), and the best of :data:`CALL_REPEATS` runs is taken:
#: on a shared machine other work only ever adds time, so the minimum of long enough runs is the steady figure
#: (timeit's rule; the median of five 2000-call runs moved single cells by up to half between reruns).  The
#: implementations of a case take their runs in turn (:func:`interleaved_best_us`), so that a slow spell of the
#: machine falls on all of them and their ratios hold.
CALL_RUN_SECONDS = 0.1
CALL_REPEATS = 9


@functools.lru_cache(maxsize=None)
def _call_loop(arity: int, keyword: bool):
    """``loop(fn, ring, calls, out)``: ``calls`` calls ``fn(a0, ..., out=out)`` (``out=`` only with ``keyword``) of
    the argument tuples of ``ring`` in turn, written out for ``arity`` arguments - CPython's vectorcall with a keyword
    name, as a user's loop calls it (``fn(*args, out=out)`` or a functools.partial would build a dict each call)."""
    names = ", ".join(f"a{i}" for i in range(arity))
    source = (f"def loop(fn, ring, calls, out):\n    n = len(ring)\n    for k in range(calls):\n"
              f"        {names}, = ring[k % n]\n        fn({names}{', out=out' if keyword else ''})\n")
    namespace: dict = {}
    exec(source, namespace)  # noqa: S102 - a loop of this script's own text, no outside input
    return namespace["loop"]


def _timed_calls(fn, args_ring: list[tuple], calls: int, out=None) -> float:
    loop = _call_loop(len(args_ring[0]), out is not None)
    start = time.perf_counter()
    loop(fn, args_ring, calls, out)
    return time.perf_counter() - start


def _calibrated(fn, args_ring: list[tuple], out, seconds: float) -> int:
    """A number of calls of ``fn`` that lasts at least ``seconds``."""
    calls = 1000
    while (elapsed := _timed_calls(fn, args_ring, calls, out)) < seconds:
        calls = int(calls * max(2.0, 1.2 * seconds / max(elapsed, 1e-9)))
    return calls


def interleaved_best_us(cases: dict[str, tuple], repeat: int = CALL_REPEATS,
                        seconds: float = CALL_RUN_SECONDS) -> dict[str, float]:
    """{name: microseconds per call} of each ``(fn, args_ring)`` or ``(fn, args_ring, out)`` (called with
    ``out=out``): the best of ``repeat`` rounds, each round one run of at least ``seconds`` of every function in
    turn."""
    cases = {name: (case + (None,))[:3] for name, case in cases.items()}
    counts = {name: _calibrated(fn, ring, out, seconds) for name, (fn, ring, out) in cases.items()}
    best = dict.fromkeys(cases, float("inf"))
    for _ in range(repeat):
        for name, (fn, ring, out) in cases.items():
            best[name] = min(best[name], _timed_calls(fn, ring, counts[name], out) / counts[name])
    return {name: 1e6 * value for name, value in best.items()}


def batch_ns(fn, args, n: int, repeat: int = 3) -> float:
    fn(*[a[:10] for a in args])
    best = min(_timed(fn, args) for _ in range(repeat))
    return 1e9 * best / n


def _timed(fn, args) -> float:
    start = time.perf_counter()
    fn(*args)
    return time.perf_counter() - start


# -- C timing harness -------------------------------------------------------------------

HARNESS_HEAD = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
%(includes)s

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double uniform(unsigned long *state)
{
    *state = (*state * 6364136223846793005UL + 1442695040888963407UL) & 0xffffffffffffUL;
    return ((double)*state / 281474976710656.0 - 0.5) * 6.283185307179586;
}

static double *random_array(size_t n, unsigned long *state)
{
    double *a = (double *)malloc(n * sizeof *a);
    for (size_t i = 0; i < n; ++i) {
        a[i] = uniform(state);
    }
    return a;
}

int main(int argc, char **argv)
{
    const long calls = argc > 1 ? atol(argv[1]) : 1000000;
    const size_t batch = argc > 2 ? (size_t)atol(argv[2]) : 100000;
    unsigned long state = 12345;
    double sink = 0.0;
    (void)batch;
"""

HARNESS_CASE = r"""
    {   /* %(label)s */
%(allocs)s
        double best = 1e30;
        for (int run = 0; run < 5; ++run) {
            const double start = now();
            for (long i = 0; i < calls; ++i) {
                const size_t k = (size_t)(i & %(mask)d);
                %(single_call)s;
                sink += %(first_output)s[0];
            }
            const double per = (now() - start) / (double)calls;
            best = per < best ? per : best;
        }
        printf("%(label)s single %%.2f\n", 1e9 * best);
%(beside_block)s%(batch_block)s
    }
"""

#: The single call timed again with :func:`other_code_c`'s function called after it in the same loop, and that
#: function alone: code beside the call's, as a control loop or an interpreter runs around it.
BESIDE_BLOCK = r"""
        double scratch[64];
        for (int j = 0; j < 64; ++j) {
            scratch[j] = 1e-3 * j;
        }
        best = 1e30;
        for (int run = 0; run < 5; ++run) {
            const double start = now();
            for (long i = 0; i < calls; ++i) {
                const size_t k = (size_t)(i & %(mask)d);
                %(single_call)s;
                symkin_bench_other_code(scratch);
                sink += %(first_output)s[0] + scratch[5];
            }
            const double per = (now() - start) / (double)calls;
            best = per < best ? per : best;
        }
        printf("%(label)s beside %%.2f\n", 1e9 * best);
        best = 1e30;
        for (int run = 0; run < 5; ++run) {
            const double start = now();
            for (long i = 0; i < calls; ++i) {
                symkin_bench_other_code(scratch);
                sink += scratch[5];
            }
            const double per = (now() - start) / (double)calls;
            best = per < best ? per : best;
        }
        printf("%(label)s other %%.2f\n", 1e9 * best);
"""

#: Statements of :func:`other_code_c`'s function (about 12.9 KB of machine code with GCC 12 and the servo flags).
OTHER_STATEMENTS = 800

BATCH_BLOCK = r"""
%(batch_allocs)s
        best = 1e30;
        for (int run = 0; run < 5; ++run) {
            const double start = now();
            %(batch_call)s;
            const double per = (now() - start) / (double)batch;
            best = per < best ? per : best;
            sink += %(first_batch_output)s[batch - 1];
        }
        printf("%(label)s batch %%.2f\n", 1e9 * best);
"""

HARNESS_TAIL = r"""
    printf("sink %g\n", sink);
    return 0;
}
"""


def other_code_c(statements: int = OTHER_STATEMENTS) -> str:
    """C source of ``symkin_bench_other_code(double *a)``: ``statements`` multiply-adds on a 64-entry array, each
    reading and writing other entries (``a[7i mod 64] = a[(11i + 3) mod 64] * c_i + a[(13i + 5) mod 64]``), so that
    none can be dropped and the function's machine code grows with ``statements``; compiled as a translation unit of
    its own, so that it is not inlined into the timing loop."""
    lines = [f"    a[{(7 * i) % 64}] = a[{(11 * i + 3) % 64}] * {1 + i * 1e-6!r} + a[{(13 * i + 5) % 64}];"
             for i in range(statements)]
    signature = "void symkin_bench_other_code(double *restrict a)"
    return f"{signature};\n\n{signature}\n{{\n" + "\n".join(lines) + "\n}\n"


def symkin_case_c(label: str, model_name: str, record: dict, beside: bool = False) -> str:
    """The harness block that times ``record``'s single call and its batch entry point; with ``beside``, the
    single call also with :func:`other_code_c`'s function after it in the loop (the harness then declares it and
    links its source), and that function alone."""
    vectors = [(i["name"], i["shape"][0]) for i in record["inputs"] if i["kind"] == "vector"]
    outputs = [(o["name"], int(np.prod(o["shape"], dtype=int))) for o in record["outputs"]]
    allocs = "\n".join(f"        double *in_{v} = random_array({RING} * {n}, &state);" for v, n in vectors)
    allocs += "\n" + "\n".join(f"        double out_{o}[{n}];" for o, n in outputs)
    single = f"{model_name}_{record['name']}(" + ", ".join(
        [f"in_{v} + {n} * k" for v, n in vectors] + [f"out_{o}" for o, _ in outputs]) + ")"
    batch_allocs = "\n".join(f"        double *batch_{v} = random_array(batch * {n}, &state);" for v, n in vectors)
    batch_allocs += "\n" + "\n".join(f"        double *batch_out_{o} = (double *)malloc(batch * {n} * sizeof(double));"
                                     for o, n in outputs)
    batch_call = f"{model_name}_{record['name']}_batch(batch, " + ", ".join(
        [f"batch_{v}" for v, _ in vectors] + [f"batch_out_{o}" for o, _ in outputs]) + ")"
    block = BATCH_BLOCK % {"batch_allocs": batch_allocs, "batch_call": batch_call, "label": label,
                           "first_batch_output": f"batch_out_{outputs[0][0]}"}
    fields = {"label": label, "mask": RING - 1, "single_call": single, "first_output": f"out_{outputs[0][0]}"}
    return HARNESS_CASE % {**fields, "allocs": allocs, "batch_block": block,
                           "beside_block": BESIDE_BLOCK % fields if beside else ""}


def run_harness(source: str, sources: list[Path], includes: list[Path], compiler: list[str], flags: list[str],
                work: Path, calls: int, batch: int, name: str) -> dict[tuple[str, str], float]:
    main = work / f"{name}.c"
    main.write_text(source)
    binary = work / name
    command = compiler + flags + [f"-I{d}" for d in includes] + [str(main), *map(str, sources), "-o", str(binary),
                                                                 "-lm"]
    subprocess.run(command, check=True)
    out = subprocess.run([str(binary), str(calls), str(batch)], check=True, capture_output=True, text=True).stdout
    results = {}
    for line in out.splitlines():
        parts = line.rsplit(" ", 2)
        if len(parts) == 3 and parts[1] in ("single", "batch", "beside", "other"):
            results[parts[0], parts[1]] = float(parts[2])
    return results


def function_bytes(binary: Path, symbol: str) -> int | None:
    """The size in bytes of the machine code of function ``symbol`` in ``binary`` (binutils' ``nm -S``), or None
    where nm is missing or does not list it."""
    nm = shutil.which("nm")
    if nm is None:
        return None
    listing = subprocess.run([nm, "-S", "--defined-only", str(binary)], capture_output=True, text=True).stdout
    for line in listing.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[3] == symbol:
            return int(parts[1], 16)
    return None


def instruction_cache() -> str:
    """This CPU's level-1 instruction cache as Linux reports it (e.g. "32K"), or "unknown"."""
    for index in sorted(Path("/sys/devices/system/cpu/cpu0/cache").glob("index*")):
        try:
            if (index / "level").read_text().strip() == "1" and (index / "type").read_text().strip() == "Instruction":
                return (index / "size").read_text().strip()
        except OSError:
            continue
    return "unknown"


def code_size_line(code_bytes: dict[str, int | None]) -> str:
    """The machine code of each case's single-configuration C function beside the L1 instruction cache: a call
    whose code (with its caller's: the interpreter's, from Python) exceeds the cache fetches instructions from L2 on
    every call, which costs more than its arithmetic (:func:`beside_line`)."""
    sizes = ", ".join(f"{label} {size:,}".replace(",", " ") if size is not None else f"{label} ?"
                      for label, size in code_bytes.items())
    return f"machine code of the single-configuration C functions [bytes] (L1 instruction cache " \
           f"{instruction_cache()}): {sizes}"


def beside_line(c_timings: dict[tuple[str, str], float], other_bytes: int | None) -> str:
    """Each case's single C call alone, beside :func:`other_code_c`'s function in the same loop, and the sum of the
    two apart [ns]: a loop whose code outgrows the L1 instruction cache takes longer than the sum."""
    cases = [label for label, kind in c_timings if kind == "beside"]
    size = f"{other_bytes:,}".replace(",", " ") if other_bytes is not None else "?"
    cells = [f"{label} {c_timings[label, 'single']:.0f} / {c_timings[label, 'beside']:.0f} / "
             f"{c_timings[label, 'single'] + c_timings[label, 'other']:.0f}" for label in cases]
    return f"C call alone / beside {size} bytes of other code in the loop / the two apart, summed [ns]: " \
           + ", ".join(cells)


def symforce_harness(header_dir: Path, dof: int) -> str:
    return (HARNESS_HEAD.replace("%(includes)s", '#include <Eigen/Core>\n#include "ur10e_fk_jacobian.h"')
            .replace("#define _POSIX_C_SOURCE 199309L", "")
            + r"""
    {
        double *q = random_array(%(ring)d * %(dof)d, &state);
        Eigen::Matrix<double, 4, 4> T;
        Eigen::Matrix<double, 6, %(dof)d> J;
        double best = 1e30;
        for (int run = 0; run < 5; ++run) {
            const double start = now();
            for (long i = 0; i < calls; ++i) {
                const size_t k = (size_t)(i & %(mask)d);
                Eigen::Map<const Eigen::Matrix<double, %(dof)d, 1>> qk(q + %(dof)d * k);
                sym::Ur10EFkJacobian<double>(qk, &T, &J);
                sink += T(0, 3);
            }
            const double per = (now() - start) / (double)calls;
            best = per < best ? per : best;
        }
        printf("FK+J single %%.2f\n", 1e9 * best);
    }
""" % {"ring": RING, "dof": dof, "mask": RING - 1} + HARNESS_TAIL)


# -- main -----------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=100_000, help="configurations per batched call (default 1e5)")
    parser.add_argument("--calls", type=int, default=1_000_000, help="single calls per C timing run (default 1e6)")
    parser.add_argument("--cflags", default=SERVO_CFLAGS,
                        help="flags for the generated C, the C harness and SymForce (default: %(default)s; "
                             "'-O3 -march=native' keeps every product and sum rounded apart, as ISO C99 does)")
    parser.add_argument("--no-symforce", action="store_true", help="skip SymForce")
    args = parser.parse_args(argv)
    compiler = [os.environ.get("CC", "cc")]
    cflags = args.cflags.split()
    model = load_model(MODEL)
    rng = np.random.default_rng(0)
    work = Path(tempfile.mkdtemp(prefix="symkin-bench-"))
    os.environ.setdefault("SYMKIN_CACHE_DIR", str(work / "cache"))
    os.environ.setdefault("SYMKIN_CFLAGS", args.cflags)
    try:
        cases = find_cases(model)
        try:
            pm, tcp = pinocchio_model(model)
        except ImportError:
            pm, tcp = None, None
            print("Pinocchio: not installed (pip install pin==4.1.0); its rows are left out")
        rows = {}
        empty_calls: dict[str, float] = {}
        out_calls: dict[str, float] = {}
        c_timings: dict[tuple[str, str], float] = {}
        op_counts = {}
        code_bytes: dict[str, int | None] = {}
        other_code = work / "other_code.c"
        other_code.write_text(other_code_c())
        for label, quantities in cases.items():
            target = generate(model, quantities, work / label.replace("+", "_"))
            name = function_name(quantities)
            record = next(f for f in load(target).manifest["functions"] if f["name"] == name)
            op_counts[label] = record["op_counts"]["cse"]
            inputs = random_inputs(record, args.batch, rng)
            ring = [tuple(a[k] for a in inputs) for k in range(RING)]
            functions = {f"symkin {backend}": getattr(load(target, backend=backend), name)
                         for backend in ("numpy", "c", "casadi")}
            os.environ[ENTRY_VARIABLE] = "ctypes"                  # the same library through ctypes alone
            functions["symkin c (ctypes)"] = getattr(load(target, backend="c"), name)
            del os.environ[ENTRY_VARIABLE]
            out = tuple(np.empty(o["shape"]) for o in record["outputs"])
            into = out[0] if len(out) == 1 else out
            calls = {impl: (fn, ring) for impl, fn in functions.items()}
            calls["empty"] = (id, [(a[0],) for a in ring])
            calls["out"] = (functions["symkin c"], ring, into)
            if pm is not None:
                calls["pinocchio"] = (pinocchio_call(label, pm, tcp), ring)
            per_call = interleaved_best_us(calls)
            for impl, fn in functions.items():
                rows[label, impl] = (per_call[impl], batch_ns(fn, inputs, args.batch))
            empty_calls[label], out_calls[label] = per_call["empty"], per_call["out"]
            includes = f'#include "{model.name}.h"\nvoid symkin_bench_other_code(double *restrict a);'
            source = HARNESS_HEAD % {"includes": includes} + symkin_case_c(label, model.name, record, beside=True) \
                + HARNESS_TAIL
            harness = f"harness_{label.replace('+', '_')}"
            c_timings.update(run_harness(source, [target / f"{model.name}.c", other_code], [target], compiler,
                                         ["-std=c99", *cflags], work, args.calls, args.batch, harness))
            code_bytes[label] = function_bytes(work / harness, f"{model.name}_{name}")
            if pm is not None:
                rows[label, "pinocchio"] = (per_call["pinocchio"], pinocchio_batch_ns(calls["pinocchio"][0], inputs,
                                                                                    args.batch))
        symforce_note = ""
        if not args.no_symforce:
            symforce_note = symforce_timings(model, work, cflags, args.calls, c_timings)
        table = []
        for (label, impl), (call_us, per_config) in rows.items():
            c_call = c_timings.get((label, "single")) if impl == "symkin c" else None
            c_batch = c_timings.get((label, "batch")) if impl == "symkin c" else None
            table.append([label, impl, f"{call_us:.2f}", f"{per_config:.0f}",
                          f"{c_call:.1f}" if c_call else "", f"{c_batch:.1f}" if c_batch else ""])
            if impl == "symkin casadi" and (f"sf:{label}", "single") in c_timings:
                table.append([label, "symforce (C++)", "", "", f"{c_timings[f'sf:{label}', 'single']:.1f}", ""])
        print(f"UR10e evaluation speed, {args.batch} configurations per batch, C flags '{args.cflags}', "
              f"all parameters folded")
        print("op counts after CSE: " + ", ".join(f"{k} {v}" for k, v in op_counts.items()))
        print(code_size_line(code_bytes))
        print(beside_line(c_timings, function_bytes(work / harness, "symkin_bench_other_code")))  # in every harness
        print(format_table(["case", "implementation", "py call [us]", "py batch [ns/config]", "C call [ns]",
                            "C batch [ns/config]"], table))
        if symforce_note:
            print(symforce_note)
        print(python_call_summary(rows, empty_calls, out_calls, c_timings))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


def python_call_summary(rows, empty_calls, out_calls, c_timings) -> str:
    """The compiled entry points' Python call, with and without ``out=``, beside ctypes, Pinocchio's binding and the
    floor (an empty CPython call of a builtin plus the C time), with the targets of issues 34 and 65."""
    table = []
    for label, empty in empty_calls.items():
        compiled, plain = rows[label, "symkin c"][0], rows[label, "symkin c (ctypes)"][0]
        pinocchio = rows.get((label, "pinocchio"), (float("nan"),))[0]
        floor = empty + 1e-3 * c_timings.get((label, "single"), float("nan"))
        table.append([label, f"{compiled:.3f}", f"{out_calls[label]:.3f}", f"{plain:.2f}", f"{pinocchio:.2f}",
                      f"{floor:.3f}", f"{pinocchio / compiled:.1f}x", f"{pinocchio / out_calls[label]:.1f}x"])
    return ("Python call, one configuration [us] (targets: FK, M <= 0.4, M+V+G <= 0.6, each >= 2.5x faster than "
            "Pinocchio's binding; dtau <= 0.6 and >= 6x, dqdd <= 1.0)\n"
            + format_table(["case", "compiled entry", "with out=", "ctypes", "pinocchio", "floor (empty call + C)",
                            "vs pinocchio", "with out= vs pinocchio"], table))


def pinocchio_call(label, pm, tcp):
    """Pinocchio's Python calls of a case for one configuration (see the module docstring)."""
    import pinocchio as pin

    data = pm.createData()
    zero = np.zeros(pm.nv)
    if label == "FK":
        def call(q):
            pin.forwardKinematics(pm, data, q)
            pin.updateFramePlacement(pm, data, tcp)
            return data.oMf[tcp].homogeneous
    elif label == "FK+J":
        def call(q):
            J = pin.computeFrameJacobian(pm, data, q, tcp, pin.LOCAL_WORLD_ALIGNED)
            return data.oMf[tcp].homogeneous, J
    elif label == "M":
        def call(q):
            return pin.crba(pm, data, q)
    elif label == "dtau":
        def call(q, qd, qdd):
            return pin.computeRNEADerivatives(pm, data, q, qd, qdd)
    elif label == "dqdd":
        def call(q, qd, tau):
            return pin.computeABADerivatives(pm, data, q, qd, tau)
    else:
        def call(q, qd):
            M = pin.crba(pm, data, q).copy()
            return M, pin.rnea(pm, data, q, qd, zero).copy(), pin.computeGeneralizedGravity(pm, data, q).copy()
    return call


def pinocchio_batch_ns(call, inputs, n):
    """Nanoseconds per configuration of a Python loop of Pinocchio's ``call`` over the batch."""
    def loop(*arrays):
        for k in range(len(arrays[0])):
            call(*[a[k] for a in arrays])

    return batch_ns(loop, inputs, n)


def symforce_timings(model, work, cflags, calls, c_timings) -> str:
    try:
        import symforce  # noqa: F401
    except ImportError:
        return "SymForce: not installed (pip install symforce==0.12.0)"
    eigen = next((p for p in (Path("/usr/include/eigen3"), Path("/usr/local/include/eigen3")) if p.exists()), None)
    cxx = shutil.which(os.environ.get("CXX", "c++"))
    if eigen is None or cxx is None:
        return "SymForce: skipped, needs a C++ compiler and the Eigen headers (apt-get install g++ libeigen3-dev)"
    header_dir = symforce_fk_jacobian_codegen(model, work / "symforce")
    source = symforce_harness(header_dir, model.dof)
    results = run_harness(source, [], [header_dir, eigen], [cxx], ["-std=c++17", *cflags, "-x", "c++"], work,
                          calls, 1, "harness_symforce")
    c_timings.update({(f"sf:{label}", kind): v for (label, kind), v in results.items()})
    ops = next((line for line in (header_dir / f"{model.name}_fk_jacobian.h").read_text().splitlines()
                if "Total ops" in line), "").strip().lstrip("/ ")
    return f"SymForce FK+J: sf.Pose3 chain + pose.jacobian(q) (tangent-space Jacobian), {ops}"


if __name__ == "__main__":
    raise SystemExit(main())

"""Cost of the stability harness's 50-digit reference: FLINT's arb balls against mpmath.

Run with `make bench` or `python benchmarks/bench_reference.py [--states N]`.

The un-optimized expressions of the example Stewart platform (models/stewart.yaml: the largest
example, its dynamics thousands of operations long) are evaluated at N random states by the
harness's reference (symkin.stability.reference.BallReference: sympy's mpmath printer onto arb
balls, 256-bit midpoints) and by plain mpmath at 50 digits (the harness's reference until
2026-11-26), in this process.  Printed per quantity: the time per state of each, their ratio, and
the largest relative difference between the two references (both keep 50 digits: about 1e-45).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import mpmath  # noqa: E402
import numpy as np  # noqa: E402

from symkin.derivation import Derivation  # noqa: E402
from symkin.ir.evaluate import lambdify_spec  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.stability.reference import DIGITS, BallReference  # noqa: E402
from symkin.stability.states import scaled_home_pose, parameter_values  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

QUANTITIES = ("closure", "jacobian", "mass_matrix", "coriolis_vector", "inverse_dynamics")


def per_state(function, states: list) -> tuple[float, list]:
    start = time.perf_counter()
    values = [function(state) for state in states]
    return (time.perf_counter() - start) / len(states), values


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=20, help="random states per quantity (default 20)")
    args = parser.parse_args()
    model = load_model(ROOT / "models" / "stewart.yaml")
    derivation = Derivation(model)
    parameters = parameter_values(model)
    home = np.asarray(scaled_home_pose(model), dtype=float)
    rows = []
    for name in QUANTITIES:
        spec = derivation[name]
        ball = BallReference(spec)
        symbols = [s for i in spec.vector_inputs for s in i.symbols] + [i.symbols[0] for i in spec.parameter_inputs]
        plain = lambdify_spec(spec, symbols, modules="mpmath")
        rng = np.random.default_rng(1)  # inputs near the home pose (p = 0 is the platform at its base height)
        states = [{i.name: rng.uniform(-0.05, 0.05, len(i.symbols)) + (home if i.name == "p" else 0)
                   for i in spec.vector_inputs} for _ in range(args.states)]

        def with_mpmath(vectors):
            inputs = [mpmath.mpf(float(v)) for i in spec.vector_inputs for v in vectors[i.name]]
            inputs += [mpmath.mpf(float(parameters[i.name])) for i in spec.parameter_inputs]
            with mpmath.workdps(DIGITS):
                return [mpmath.mpf(v) for v in plain(*inputs)]

        t_ball, exact_ball = per_state(lambda v: ball.exact(v, parameters), states)
        t_mpmath, exact_mpmath = per_state(with_mpmath, states)
        with mpmath.workdps(DIGITS):
            difference = max(float(abs(a - b) / max(abs(b), mpmath.mpf(1e-30)))
                             for xs, ys in zip(exact_ball, exact_mpmath) for a, b in zip(xs, ys) if not mpmath.isnan(a))
        rows.append((name, f"{1e3 * t_ball:.2f}", f"{1e3 * t_mpmath:.2f}", f"{t_mpmath / t_ball:.1f}", f"{difference:.1e}"))
    print(f"50-digit reference of stewart, {args.states} random states per quantity (ms per state)")
    print(format_table(("quantity", "arb", "mpmath", "mpmath / arb", "largest relative difference"), rows))


if __name__ == "__main__":
    main()

"""UR10e dynamics: symkin's derive time next to sympy.physics.mechanics (Lagrange and Kane).

symkin derives FK, the task Jacobian, M, V, C, G and joint friction of models/ur10e.yaml
(with illustrative friction coefficients added: Universal Robots publishes none) and emits
the numpy module - everything ``symkin derive`` does, timed from loading the model to the
emitted text (median of --repeat runs, each with a fresh derivation graph).

The competitors build the same robot (the frames, masses and inertia tensors of the same
symkin model, symbolic parameters) with sympy.physics.mechanics and form the equations of
motion: ``LagrangesMethod`` (Lagrangian with the potential energy of gravity) and
``KanesMethod`` (gravity as loads), then ask for the mass matrix and the forcing vector,
without simplification and without emitting code.  Each runs once, in a subprocess capped
at --cap seconds; a capped run is reported as "> cap".

Run with `make bench` or `python benchmarks/bench_dynamics.py [--repeat N] [--cap SECONDS]`.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.text_table import format_table  # noqa: E402

MODEL = ROOT / "models" / "ur10e.yaml"
OUTPUTS = ("fk", "jacobian", "mass_matrix", "coriolis_vector", "coriolis_matrix", "gravity_vector", "friction")
#: Illustrative joint friction (viscous N*m*s/rad, Coulomb N*m) so that 'friction' has something to derive.
FRICTION = """
friction:
  q1: {viscous: 2.0, coulomb: 4.0}
  q2: {viscous: 2.0, coulomb: 4.0}
  q3: {viscous: 1.5, coulomb: 3.0}
  q4: {viscous: 0.5, coulomb: 1.0}
  q5: {viscous: 0.5, coulomb: 1.0}
  q6: {viscous: 0.5, coulomb: 1.0}
"""


def bench_model():
    from symkin.model import model_from_text

    return model_from_text(MODEL.read_text() + FRICTION, "ur10e", str(MODEL))


def run_symkin() -> dict[str, float]:
    """One full derive of OUTPUTS: load, derive, optimize, emit (seconds)."""
    from symkin import pipeline

    start, cpu = time.perf_counter(), time.process_time()
    model = bench_model()
    request = pipeline.Request(outputs=OUTPUTS, fixed=(), backends=("numpy",))
    result = pipeline.generate(model, request)
    total = time.perf_counter() - start
    return {"derive": sum(r.derive_seconds for r in result.reports),
            "optimize": sum(r.optimize_seconds for r in result.reports),
            "emit": result.emit_seconds, "total": total, "cpu": time.process_time() - cpu,
            "ops": sum(r.op_counts["cse"] for r in result.reports)}


# --------------------------------------------------------------------------- competitors

def _mechanics_system():
    """The UR10e of the symkin model as sympy.physics.mechanics frames, points and rigid bodies."""
    from sympy.physics import mechanics as me

    from symkin.model.schema import JointType, Rotation

    model = bench_model()
    n = model.dof
    q = me.dynamicsymbols(f"q1:{n + 1}")
    N = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(N, 0)
    frame, point = N, origin
    counter = [0]

    def new_frame():
        counter[0] += 1
        return me.ReferenceFrame(f"F{counter[0]}")

    def new_point_name():
        counter[0] += 1
        return f"P{counter[0]}"

    def apply(ops):
        nonlocal frame, point
        for op in ops:
            if isinstance(op, Rotation):
                child = new_frame()
                child.orient_axis(frame, frame.x * op.axis[0] + frame.y * op.axis[1] + frame.z * op.axis[2], op.angle)
                frame = child
            else:
                moved = point.locatenew(new_point_name(),
                                        op.vector[0] * frame.x + op.vector[1] * frame.y + op.vector[2] * frame.z)
                moved.v2pt_theory(point, N, frame)
                point = moved

    apply(model.base)
    links = {}
    for k, joint in enumerate(model.joints):
        if joint.type is not JointType.REVOLUTE:
            raise NotImplementedError("the comparison model has revolute joints only")
        apply(joint.before)
        child = new_frame()
        axis = joint.axis
        # orient_axis also sets the angular velocity q_k' * axis; the joint origin stays in place.
        child.orient_axis(frame, frame.x * axis[0] + frame.y * axis[1] + frame.z * axis[2], q[k] + joint.offset)
        frame = child
        apply(joint.after)
        links[joint.link] = (frame, point)
    gravity = model.gravity[0] * N.x + model.gravity[1] * N.y + model.gravity[2] * N.z
    bodies, loads = [], []
    for b, body in enumerate(model.bodies):
        frame, point = links[body.link]
        com = point.locatenew(f"C{b}", body.com[0] * frame.x + body.com[1] * frame.y + body.com[2] * frame.z)
        com.v2pt_theory(point, N, frame)
        I = body.inertia
        dyadic = me.inertia(frame, I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[1, 2], I[0, 2])
        rigid = me.RigidBody(f"B{b}", com, frame, body.mass, (dyadic, com))
        rigid.potential_energy = -body.mass * gravity.dot(com.pos_from(origin))
        bodies.append(rigid)
        loads.append((com, body.mass * gravity))
    return q, N, bodies, loads


def run_lagrange() -> None:
    from sympy.physics import mechanics as me

    q, N, bodies, _ = _mechanics_system()
    L = me.Lagrangian(N, *bodies)
    method = me.LagrangesMethod(L, q, frame=N)
    method.form_lagranges_equations()
    method.mass_matrix
    method.forcing


def run_kane() -> None:
    from sympy.physics import mechanics as me

    q, N, bodies, loads = _mechanics_system()
    u = me.dynamicsymbols(f"u1:{len(q) + 1}")
    kd = [qi.diff(me.dynamicsymbols._t) - ui for qi, ui in zip(q, u)]
    method = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    method.kanes_equations(bodies, loads)
    method.mass_matrix
    method.forcing


COMPETITORS = {"LagrangesMethod": run_lagrange, "KanesMethod": run_kane}


def run_capped(name: str, cap: float) -> tuple[float, float] | None:
    """(wall, CPU) seconds of competitor ``name`` in a subprocess, or None if it hit the cap."""
    try:
        done = subprocess.run([sys.executable, __file__, "--competitor", name], capture_output=True, text=True,
                              timeout=cap, check=True)
    except subprocess.TimeoutExpired:
        return None
    record = json.loads(done.stdout.strip().splitlines()[-1])
    return float(record["seconds"]), float(record["cpu"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5, help="symkin runs (median reported)")
    parser.add_argument("--cap", type=float, default=180.0, help="time limit per competitor run, seconds")
    parser.add_argument("--skip-competitors", action="store_true", help="time symkin only")
    parser.add_argument("--competitor", choices=tuple(COMPETITORS), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.competitor:
        start, cpu = time.perf_counter(), time.process_time()
        COMPETITORS[args.competitor]()
        print(json.dumps({"seconds": time.perf_counter() - start, "cpu": time.process_time() - cpu}))
        return 0
    runs = [run_symkin() for _ in range(args.repeat)]
    ours = {k: statistics.median(r[k] for r in runs) for k in ("derive", "optimize", "emit", "total", "cpu")}
    print(f"UR10e: {', '.join(OUTPUTS)}; symkin median of {args.repeat} runs, "
          f"{runs[0]['ops']} operations in the emitted code")
    print(format_table(["stage", "seconds"], [[k, f"{v:.3f}"] for k, v in ours.items()]))
    if args.skip_competitors:
        return 0
    rows = [["symkin (derive + optimize + emit)", f"{ours['total']:.2f}", f"{ours['cpu']:.2f}", "1", "1"]]
    for name in COMPETITORS:
        label = f"sympy.physics.mechanics {name} (M, forcing)"
        measured = run_capped(name, args.cap)
        if measured is None:
            rows.append([label, f"> {args.cap:.0f}", "-", f"> {args.cap / ours['total']:.0f}", "-"])
        else:
            wall, cpu = measured
            rows.append([label, f"{wall:.2f}", f"{cpu:.2f}", f"{wall / ours['total']:.1f}", f"{cpu / ours['cpu']:.1f}"])
    print()
    print("wall-clock and CPU seconds (CPU time is the fairer figure on a shared, loaded machine)")
    print(format_table(["method", "wall s", "CPU s", "wall / symkin", "CPU / symkin"], rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

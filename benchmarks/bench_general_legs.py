"""Legs without the distance form at servo rate (issue 63's baseline): the Novint Falcon of
models/devices/novint_falcon.yaml beside the closed-form DELTA of models/delta.yaml, in the same process.

For each backend (numpy, C) and device, one haptic-loop step at a time along a slow path of the arms (a
circle of 5 deg in each arm, 1000 samples): the forward kinematics warm-started from the previous sample and
the Jacobian J = dp/dq there (the run-time mechanism's ClosureAssembly: the forward kinematics only).  The Falcon runs the run-time Gauss-Newton on its generated closure
(``solve_closure``, unknowns p and s) and ``closure_velocities``, and the generated assembly of its C library
(``novint_falcon_assemble`` and ``novint_falcon_assembly_jacobian``) from Python (``GeneratedAssembly``, its compiled
entry points unless ``SYMKIN_C_ENTRY=ctypes``) and from a C loop
(compiled here with the library's source); the DELTA its generated closed forms ``fk`` and ``jacobian``.  Issue
63's targets: the Falcon's fk + J warm-started <= 5 us per call in C and <= 10 us from Python.

Then the workspace of each device as ``symkin workspace DIR --backend c --no-figure`` computes it (its scene's
functions, the C backend; the time the command reports, "done in"): the Falcon's home assembly continued over a
Cartesian grid, the DELTA's joint space sampled through its closed-form fk (also on the numpy backend: the Falcon's
continuation by the run-time solver instead of the generated inverse); and its datasheet as ``symkin rate DIR
--backend c`` computes it (the time it reports).  Issue 63's target: the Falcon within 3x of the DELTA.

Last, ``symkin simulate MODEL.yaml --scenario haptic-wall --duration 1 --backend c`` (the time it reports) of a model
file derived on the fly: the Novint Falcon (three legs with parallelograms and offsets) carrying bodies by
models/delta.yaml's recipe (none are published for the Falcon: the time depends on the topology, not on the masses),
docs/model-format.md's closure DELTA (legs without the distance form) carrying the DELTA's bodies (the masses of
models/delta.yaml), beside models/delta.yaml itself (closed forms).  Issue 63's target: at least
real time (1 s of the haptic loop in at most 1 s).  Beside it, what a step of that simulation spends on the dynamics in
the actuated coordinates at one state (``actuated_dynamics``): the generated ``<model>_actuated_dynamics`` (C,
through ``GeneratedAssembly``); the C library's terms over z projected at run time (numpy, A^+ by QR), for one state
(the generated functions' single-state entry points) and as a batch of one (their batch entry points); the numpy
backend's terms projected for one state.

Run with `make bench` or `python benchmarks/bench_general_legs.py [--samples N]`.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin.mechanism.closure import ClosureAssembly, solve_home_assembly  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.runtime.assembly import GeneratedAssembly  # noqa: E402
from symkin.runtime.closure_dynamics import actuated_dynamics  # noqa: E402
from symkin.runtime.parallel import closure_velocities, solve_closure  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

def _path(centre: np.ndarray, samples: int) -> np.ndarray:
    """Arm angles along a circle of 5 deg about ``centre`` in each arm, phase-shifted (samples, 3)."""
    t = np.linspace(0.0, 2 * np.pi, samples)
    return centre + np.radians(5.0) * np.sin(t[:, None] + np.array([0.0, 2.1, 4.2]))


def _per_call(step, path: np.ndarray, repeat: int) -> float:
    """Median over ``repeat`` runs of the time per sample (s) of ``step`` along ``path``."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        for q in path:
            step(q)
        times.append((time.perf_counter() - start) / len(path))
    return statistics.median(times)


def _falcon_step(model):
    """One warm-started forward kinematics and Jacobian of the Falcon, from the last sample's (s, p)."""
    home = solve_home_assembly(model)
    state = {"s": home.s, "p": np.asarray(model.info.home, dtype=float)}

    def step(q: np.ndarray) -> None:
        report = solve_closure(model, q, state["s"], state["p"], unknowns=("p", "s"))
        state["s"], state["p"] = report.solution["s"], report.solution["p"]
        closure_velocities(model, q, state["s"], state["p"])

    return step, home.q


def _generated_step(model):
    """The same step by the generated assembly of the Falcon's C library (every parameter folded), from Python
    (:class:`symkin.runtime.assembly.GeneratedAssembly`)."""
    assembly = GeneratedAssembly(model)
    home = solve_home_assembly(model)       # the model file's declared home assembly, refined
    s, p, J = home.s.copy(), np.asarray(model.info.home, dtype=float), np.empty((3, 3))

    def step(q: np.ndarray) -> None:
        if assembly.assemble(q, s, p)[0] <= 0:
            raise RuntimeError("the generated assembly lost the path or its assembly mode")
        assembly.jacobian(q, s, p, J)

    return step, home.q, s, p


C_LOOP = r"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <math.h>
#include <time.h>
#include "novint_falcon.h"
int main(void) {
    double s[12] = {%(s)s}, p[3] = {%(p)s}, q[3], J[9], residual;
    const int samples = %(samples)d, repeat = %(repeat)d;
    double best = 1e300;
    for (int r = 0; r < repeat; ++r) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (int k = 0; k < samples; ++k) {
            const double t = 6.283185307179586 * k / (samples - 1);
            for (int i = 0; i < 3; ++i)
                q[i] = %(arm)r + 0.08726646259971647 * sin(t + 2.1 * i);
            if (novint_falcon_assemble(q, s, p, 50, 1e-12, &residual) <= 0) return 1;
            novint_falcon_assembly_jacobian(q, s, p, J);
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        const double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        if (seconds < best) best = seconds;
    }
    printf("%%.3f\n", 1e6 * best / samples);
    return 0;
}
"""


def _c_loop(directory: Path, s: np.ndarray, p: np.ndarray, arm: float, samples: int, repeat: int) -> float:
    """us per step of the generated assembly called from a C loop (cc -O3), the same path from (s, p)."""
    source = directory / "loop.c"
    source.write_text(C_LOOP % {"s": ", ".join(repr(float(v)) for v in s), "p": ", ".join(repr(float(v)) for v in p),
                                "samples": samples, "repeat": repeat, "arm": float(arm)})
    binary = directory / "loop"
    subprocess.run(["cc", "-std=c99", "-O3", "-o", str(binary), str(source), str(directory / "novint_falcon.c"),
                    "-lm"], check=True)
    return float(subprocess.run([str(binary)], check=True, capture_output=True, text=True).stdout)


def _delta_step(model):
    def step(q: np.ndarray) -> None:
        p = model.fk(q).position
        model.jacobian(q, p)

    return step, np.radians([39.0, 39.0, 39.0])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000, help="samples of the path (default: %(default)s)")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        falcon_dir = symkin.derive(ROOT / "models" / "devices" / "novint_falcon.yaml", tmp,
                                   outputs=["closure", "closure_jacobians"], backends=["numpy", "c"])
        delta_dir = symkin.derive(ROOT / "models" / "delta.yaml", tmp, outputs=["fk", "jacobian"],
                                  backends=["numpy", "c"])
        folded = symkin.derive(ROOT / "models" / "devices" / "novint_falcon.yaml", Path(tmp) / "folded",
                               outputs=["closure", "closure_jacobians"], backends=["numpy", "c"], fixed=["all"])
        for backend in ("numpy", "c"):
            for device, directory, make in (("Novint Falcon (general legs)", falcon_dir, _falcon_step),
                                            ("DELTA (closed forms)", delta_dir, _delta_step)):
                step, centre = make(symkin.load(directory, backend))
                seconds = _per_call(step, _path(centre, args.samples), args.repeat)
                rows.append([device, backend, f"{1e6 * seconds:.1f}"])
        for backend in ("numpy", "c"):    # the run-time mechanism's continuation: fk only
            mechanism = ClosureAssembly(symkin.load(folded, backend))
            seconds = _per_call(mechanism, _path(mechanism.home, args.samples), args.repeat)
            rows.append(["Novint Falcon, ClosureAssembly (fk only)",
                         "c, generated assembly" if mechanism.generated else backend, f"{1e6 * seconds:.1f}"])
        step, centre, s, p = _generated_step(symkin.load(folded, "c"))
        seconds = _per_call(step, _path(centre, args.samples), args.repeat)
        rows.append(["Novint Falcon, generated assembly", "c, from Python", f"{1e6 * seconds:.2f}"])
        rows.append(["Novint Falcon, generated assembly", "c, from C", f"{_c_loop(folded, s, p, centre[0], args.samples, args.repeat):.2f}"])
        workspace = []
        for device, model in (("Novint Falcon (general legs, continued)", "devices/novint_falcon.yaml"),
                              ("DELTA (closed forms, sampled)", "delta.yaml")):
            directory = symkin.derive(ROOT / "models" / model, Path(tmp) / "scene")
            workspace.append([device, f"{_workspace_seconds(directory, 'c'):.2f}",
                              f"{_workspace_seconds(directory, 'numpy'):.2f}", f"{_rate_seconds(directory):.2f}"])
    print(format_table(["device", "backend", "fk + J per call, warm (us)"], rows))
    print("issue 63's targets for the Falcon: <= 5 us per call in C, <= 10 us from Python")
    print(format_table(["device", "symkin workspace --backend c (s)", "--backend numpy (s)",
                        "symkin rate --backend c (s)"], workspace))
    print("issue 63's target: the Falcon's workspace and rating within 3x of the DELTA's time")
    with tempfile.TemporaryDirectory() as tmp:
        simulated = [[device, f"{_simulate_seconds(path, Path(tmp) / 'simulate'):.2f}"]
                     for device, path in (("Novint Falcon with bodies (general legs, offsets)", _falcon_file(Path(tmp))),
                                          ("closure DELTA (general legs, model file)", _closure_delta_file(Path(tmp))),
                                          ("DELTA (closed forms, model file)", ROOT / "models" / "delta.yaml"))]
    print(format_table(["device", "symkin simulate --scenario haptic-wall --duration 1 --backend c (s)"], simulated))
    print("issue 63's target: at least real time (<= 1 s)")
    print(format_table(["closure DELTA with bodies: actuated dynamics of one state", "us per call"],
                       _projection_rows(args.repeat)))
    return 0


def _projection_rows(repeat: int) -> list[list[str]]:
    """The dynamics in the actuated coordinates of one assembled state of the closure DELTA with bodies: C, numpy
    (one state), numpy (a batch of one)."""
    with tempfile.TemporaryDirectory() as tmp:
        directory = symkin.derive(_closure_delta_file(Path(tmp)), tmp, backends=["numpy", "c"],
                                  outputs=["closure", "closure_jacobians", "closure_dynamics"], fixed=["all"])
        c_model, numpy_model = symkin.load(directory, "c"), symkin.load(directory)
        mechanism = ClosureAssembly(c_model)
        q = mechanism.home + 0.05
        s, p = mechanism(q)
        qd = np.array([0.3, -0.2, 0.1])
        calls = [("C: <model>_actuated_dynamics", lambda: actuated_dynamics(c_model, q, s, p, qd, mechanism.generated)),
                 ("C terms, projected in numpy (one state)", lambda: actuated_dynamics(c_model, q, s, p, qd)),
                 ("C terms, projected in numpy (a batch of one)",
                  lambda: actuated_dynamics(c_model, q[None], s[None], p[None], qd[None])),
                 ("numpy terms, projected in numpy (one state)", lambda: actuated_dynamics(numpy_model, q, s, p, qd))]
        rows = []
        for label, call in calls:
            count = 2000
            best = min(_seconds(call, count) for _ in range(repeat))
            rows.append([label, f"{1e6 * best / count:.1f}"])
    return rows


def _seconds(call, count: int) -> float:
    start = time.perf_counter()
    for _ in range(count):
        call()
    return time.perf_counter() - start


def _bodies(arm_mass: float, a: float, rod_mass: float, b: float, platform: float, rotor: float, gear: float,
            gravity: str) -> str:
    """The gravity and bodies: lines of three legs: each arm (mass, length a) a uniform rod on its actuated joint
    theta<k>, each parallelogram one uniform rod (length b) on its swing joint swing<k>, the platform's mass and the
    rotors (inertia, gear ratio)."""
    arm, rod = arm_mass * a ** 2 / 12, rod_mass * b ** 2 / 12
    links = "".join(f"    theta{k}: {{mass: {arm_mass}, com: [{a / 2}, 0, 0], inertia: {{yy: {arm}, zz: {arm}}}}}\n"
                    f"    swing{k}: {{mass: {rod_mass}, com: [{b / 2}, 0, 0], inertia: {{yy: {rod}, zz: {rod}}}}}\n"
                    for k in (1, 2, 3))
    return (f"gravity: {gravity}\nbodies:\n  platform: {{mass: {platform}}}\n  links:\n" + links
            + f"  rotor: {{inertia: {rotor}, gear_ratio: {gear}}}\n")


def _delta_values() -> dict[str, float]:
    return {str(k): float(value) for k, value in load_model(ROOT / "models" / "delta.yaml").parameter_values.items()}


def _closure_delta_file(directory: Path) -> Path:
    """docs/model-format.md's closure DELTA with the bodies of models/delta.yaml (its masses, sourced there): each upper
    arm (m_arm) on its actuated joint, each parallelogram as one rod (m_rod) on its swing joint, the platform
    (m_platform) and the rotors (J_rotor, gear), written into ``directory``."""
    text = (ROOT / "docs" / "model-format.md").read_text()
    legs = re.search(r"cat > out/closure_delta.yaml <<'EOF_MODEL'\n(.*?)^EOF_MODEL$", text, re.S | re.M).group(1)
    v = _delta_values()
    path = directory / "closure_delta.yaml"
    path.write_text(legs + _bodies(v["m_arm"], v["a"], v["m_rod"], v["b"], v["m_platform"], v["J_rotor"], v["gear"],
                                   "[0, 0, -9.81]"))
    return path


def _falcon_file(directory: Path) -> Path:
    """models/devices/novint_falcon.yaml (its published geometry and capstan ratio; the file declares no bodies, as
    none are published) carrying bodies by models/delta.yaml's recipe for timing: its arm's and parallelogram's masses
    per unit length (handbook densities of its tubes) over the Falcon's arm a and rods b, its platform and rotor
    inertia; gravity along the Falcon's -y (libnifalcon's frame: y up).  Written into ``directory``."""
    v = _delta_values()
    a, b = 0.060, 0.1025                              # the Falcon's arm and rods (libnifalcon a and b)
    path = directory / "novint_falcon.yaml"
    path.write_text((ROOT / "models" / "devices" / "novint_falcon.yaml").read_text()
                    + _bodies(v["m_arm"] * a / v["a"], a, v["m_rod"] * b / v["b"], b, v["m_platform"], v["J_rotor"],
                              7.719, "[0, -9.81, 0]"))
    return path


def _simulate_seconds(model: Path, out: Path) -> float:
    """The time ``symkin simulate`` reports ("wrote ... in T s") for 1 s of the haptic wall on the C backend of a model
    file (derived on the fly, as a user runs it)."""
    run = subprocess.run([sys.executable, "-m", "symkin", "simulate", str(model), "--scenario", "haptic-wall",
                          "--duration", "1", "--backend", "c", "--no-figure", "-o", str(out)], capture_output=True,
                         text=True, check=True)
    wrote = [line for line in (run.stdout + run.stderr).splitlines() if line.startswith("wrote ")]
    return float(wrote[-1].split()[-2])


def _workspace_seconds(directory: Path, backend: str) -> float:
    """The time ``symkin workspace`` reports ("done in") for a model derived with its scene into ``directory``, on
    ``backend`` (numpy: the run-time solver; C: the generated inverse)."""
    run = subprocess.run([sys.executable, "-m", "symkin", "workspace", str(directory), "--backend", backend,
                          "--no-figure"], capture_output=True, text=True, check=True)
    done = [line for line in (run.stdout + run.stderr).splitlines() if line.strip().startswith("done in")]
    return float(done[-1].split()[2])


def _rate_seconds(directory: Path) -> float:
    """The time ``symkin rate`` reports ("wrote ... in T s") for a model derived into ``directory`` (effort limits
    of 1 N m: the Falcon's model file declares no drives)."""
    run = subprocess.run([sys.executable, "-m", "symkin", "rate", str(directory), "--backend", "c", "--effort-limit",
                          "1", "--no-figure", "-o", str(directory.parent / "rate")], capture_output=True, text=True,
                         check=True)
    wrote = [line for line in (run.stdout + run.stderr).splitlines() if line.startswith("wrote ")]
    return float(wrote[-1].split()[-2])


if __name__ == "__main__":
    sys.exit(main())
